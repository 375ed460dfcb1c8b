// Entry points of the two copies of store_kernel.hpp (store_o0.cpp, store_o2.cpp): run
// n scalar updates (measurement rows `rows`, n x N row after row, variance r) on the N x N
// column-major covariance P in place; return how many were accepted.
#pragma once

namespace o0 {
int updates4(double* P, const double* rows, int n, double r);
int updates6(double* P, const double* rows, int n, double r);
int updates15(double* P, const double* rows, int n, double r);
}  // namespace o0
namespace o2 {
int updates4(double* P, const double* rows, int n, double r);
int updates6(double* P, const double* rows, int n, double r);
int updates15(double* P, const double* rows, int n, double r);
}  // namespace o2

// Central-difference Jacobians: the independent reference the analytic Jacobians of every
// model are checked against.
#pragma once

#include <Eigen/Core>

namespace ctxfuse::test {

/// d f(x) / d x at x for f: R^N -> R^M, step h per coordinate.
template <int M, int N, class F>
Eigen::Matrix<double, M, N> central_jacobian(F&& f, const Eigen::Matrix<double, N, 1>& x, double h = 1e-6) {
  Eigen::Matrix<double, M, N> J;
  for (int i = 0; i < N; ++i) {
    Eigen::Matrix<double, N, 1> xp = x, xm = x;
    xp(i) += h;
    xm(i) -= h;
    J.col(i) = (f(xp) - f(xm)) / (2.0 * h);
  }
  return J;
}

}  // namespace ctxfuse::test

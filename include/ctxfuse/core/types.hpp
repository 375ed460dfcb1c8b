// Fixed-size Eigen aliases used across the engine. Every size is a compile-time constant so
// that predict/update never touch the heap.
#pragma once

#include <Eigen/Core>

namespace ctxfuse {

template <int N, class Scalar = double>
using Vector = Eigen::Matrix<Scalar, N, 1>;

template <int Rows, int Cols, class Scalar = double>
using Matrix = Eigen::Matrix<Scalar, Rows, Cols>;

template <int N, class Scalar = double>
using SquareMatrix = Matrix<N, N, Scalar>;

/// Input type of process models that take none.
struct NoInput {};

}  // namespace ctxfuse

// A Gaussian belief over a vector state: mean and covariance.
#pragma once

#include "ctxfuse/core/types.hpp"

namespace ctxfuse {

template <int N, class Scalar = double>
struct Gaussian {
  static constexpr int dim = N;
  Vector<N, Scalar> mean = Vector<N, Scalar>::Zero();
  SquareMatrix<N, Scalar> cov = SquareMatrix<N, Scalar>::Identity();
};

/// Belief of an error-state filter: a nominal state of any type (with quaternions, manifolds,
/// ...) plus the covariance of the error around it. The mean of the error is zero by
/// construction after every reset, so it is not stored.
template <class NominalState, int N>
struct ErrorStateBelief {
  static constexpr int dim = N;
  NominalState nominal{};
  SquareMatrix<N> cov = SquareMatrix<N>::Identity();
};

}  // namespace ctxfuse

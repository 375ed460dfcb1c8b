// Linear-Gaussian models: the matrices are the data. With these the EKF is the textbook
// Kalman filter, which is what the closed-form tests compare against.
#pragma once

#include "ctxfuse/core/types.hpp"

namespace ctxfuse::models {

/// x+ = F x + B u, noise Q (all fixed: dt is ignored except for validation by the filter).
template <int N, int U = 0>
struct LinearProcess {
  static constexpr int dim = N;
  using State = Vector<N>;
  using Input = std::conditional_t<U == 0, NoInput, Vector<U>>;

  SquareMatrix<N> F = SquareMatrix<N>::Identity();
  Matrix<N, (U == 0 ? 1 : U)> B = Matrix<N, (U == 0 ? 1 : U)>::Zero();
  SquareMatrix<N> Q = SquareMatrix<N>::Zero();

  State predict(const State& x, const Input& u, double /*dt*/, SquareMatrix<N>* J) const {
    if (J) *J = F;
    if constexpr (U == 0) {
      (void)u;
      return F * x;
    } else {
      return F * x + B * u;
    }
  }
  SquareMatrix<N> noise(const State&, const Input&, double) const { return Q; }
};

/// z = H x + v, v ~ N(0, R).
template <int M, int N>
struct LinearMeasurement {
  static constexpr int dim = M;
  Matrix<M, N> H = Matrix<M, N>::Zero();
  SquareMatrix<M> R = SquareMatrix<M>::Identity();

  Vector<M> predict(const Vector<N>& x, Matrix<M, N>* J) const {
    if (J) *J = H;
    return H * x;
  }
  SquareMatrix<M> noise(const Vector<N>&) const { return R; }
};

}  // namespace ctxfuse::models

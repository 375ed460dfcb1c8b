// Linear-Gaussian models: the matrices are the data. With these the EKF is the textbook
// Kalman filter, which is what the closed-form tests compare against. value<T> is the same
// map on any scalar (ceres::Jet), for the factor adapters (filters/factors.hpp).
#pragma once

#include "ctxfuse/core/types.hpp"

namespace ctxfuse::models {

/// x+ = F x + B u, noise Q (all fixed: dt is ignored except for validation by the filter).
template <int N, int U = 0>
struct LinearProcess {
  static constexpr int dim = N;
  using State = Vector<N>;
  using Input = std::conditional_t<U == 0, NoInput, Vector<U>>;
  static constexpr bool affine_in_state = true;

  SquareMatrix<N> F = SquareMatrix<N>::Identity();
  Matrix<N, (U == 0 ? 1 : U)> B = Matrix<N, (U == 0 ? 1 : U)>::Zero();
  SquareMatrix<N> Q = SquareMatrix<N>::Zero();

  template <class T>
  Vector<N, T> value(const Vector<N, T>& x, const Input& u, double /*dt*/) const {
    if constexpr (U == 0) {
      (void)u;
      return F.template cast<T>() * x;
    } else {
      return F.template cast<T>() * x + (B * u).template cast<T>();
    }
  }
  State predict(const State& x, const Input& u, double dt, SquareMatrix<N>* J) const {
    if (J) *J = F;
    return value<double>(x, u, dt);
  }
  SquareMatrix<N> noise(const State&, const Input&, double) const { return Q; }
};

/// z = H x + v, v ~ N(0, R).
template <int M, int N>
struct LinearMeasurement {
  static constexpr int dim = M;
  Matrix<M, N> H = Matrix<M, N>::Zero();
  SquareMatrix<M> R = SquareMatrix<M>::Identity();

  template <class T>
  Vector<M, T> value(const Vector<N, T>& x) const {
    return H.template cast<T>() * x;
  }
  Vector<M> predict(const Vector<N>& x, Matrix<M, N>* J) const {
    if (J) *J = H;
    return value<double>(x);
  }
  SquareMatrix<M> noise(const Vector<N>&) const { return R; }
};

}  // namespace ctxfuse::models

// Factors: the terms of a nonlinear least-squares problem over state vectors ("slots").
//
// A factor is a whitened residual r(x_1, ..., x_k) with one analytic Jacobian per slot,
// written only when its out-pointer is not null (manif's habit: callers that only need the
// cost, such as a line search or a marginalisation check, do not pay for Jacobians). Whitened
// means the cost is 1/2 |r|^2: the noise is folded in once, as the inverse of the Cholesky
// factor of its covariance, so solvers never see a covariance.
//
//   static constexpr int dim;                          // residual dimension
//   static constexpr std::array<int, k> slot_dims;     // dimension of each slot
//   Vector<dim> evaluate(const Vector<n1>&, [const Vector<n2>&,] Matrix<dim, n1>* J1 [, J2]) const;
//   template <class T> Vector<dim, T> residual(const Vector<n1, T>& [, ...]) const;
//
// The templated `residual` computes the same numbers on any scalar type: ceres::Jet flows
// through it (the tests check Ceres' automatic Jacobians against the analytic ones), so a
// Kalman update, this library's Gauss-Newton solver and Ceres all evaluate one model.
//
// Here: the concepts, whitening, `difference` with Jacobians and the Gaussian prior factor.
// filters/factors.hpp adapts the existing models: a measurement model gives a unary factor
// h(x) - z, a process model a binary one x_{k+1} [-] f(x_k, u).
#pragma once

#include <array>
#include <concepts>

#include "ctxfuse/core/concepts.hpp"
#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/validation.hpp"

namespace ctxfuse {

template <class F>
concept Factor = requires {
  { F::dim } -> std::convertible_to<int>;
  F::slot_dims.size();
};

template <class F>
concept UnaryFactor = Factor<F> && (F::slot_dims.size() == 1) &&
                      requires(const F& f, const Vector<F::slot_dims[0]>& x, Matrix<F::dim, F::slot_dims[0]>* J) {
                        { f.evaluate(x, J) } -> std::convertible_to<Vector<F::dim>>;
                      };

template <class F>
concept BinaryFactor = Factor<F> && (F::slot_dims.size() == 2) &&
                       requires(const F& f, const Vector<F::slot_dims[0]>& a, const Vector<F::slot_dims[1]>& b,
                                Matrix<F::dim, F::slot_dims[0]>* Ja, Matrix<F::dim, F::slot_dims[1]>* Jb) {
                         { f.evaluate(a, b, Ja, Jb) } -> std::convertible_to<Vector<F::dim>>;
                       };

/// L^-1 of a lower-triangular L with a non-zero diagonal, by forward substitution on the
/// identity, as straight-line fixed-size code: Eigen's triangular solve with a matrix
/// right-hand side runs its blocked dynamic-size kernel (packing included) even for a 4 x 4.
template <int M>
void lower_triangular_inverse(const SquareMatrix<M>& L, SquareMatrix<M>& Li) {
  Li.setZero();
  for (int j = 0; j < M; ++j) {
    Li(j, j) = 1.0 / L(j, j);
    for (int i = j + 1; i < M; ++i) {
      double acc = 0.0;
      for (int k = j; k < i; ++k) acc += L(i, k) * Li(k, j);
      Li(i, j) = -acc / L(i, i);
    }
  }
}

/// W with W' W = C^-1 for a covariance C = L L' (W = L^-1, lower triangular), so that
/// |W r|^2 = r' C^-1 r. Problem::none, or why C cannot whiten (not finite, not positive definite).
template <int M>
Problem whitening_from_covariance(const SquareMatrix<M>& C, SquareMatrix<M>& W) {
  if (!all_finite(C)) return Problem::non_finite_covariance;
  SquareMatrix<M> L;
  if (!cholesky_lower<M>(C, L)) return Problem::covariance_not_positive_definite;
  lower_triangular_inverse<M>(L, W);
  return all_finite(W) ? Problem::none : Problem::covariance_not_positive_definite;
}

/// W with W' W = Lambda for an information matrix Lambda = L L' (W = L', upper triangular).
template <int M>
Problem whitening_from_information(const SquareMatrix<M>& Lambda, SquareMatrix<M>& W) {
  if (!all_finite(Lambda)) return Problem::non_finite_covariance;
  SquareMatrix<M> L;
  if (!cholesky_lower<M>(Lambda, L)) return Problem::system_not_positive_definite;
  W = L.transpose();
  return Problem::none;
}

/// a [-] b with its Jacobians (d/da, d/db) for a process model's state: the model's own
/// `difference(a, b, Ja, Jb)` when it has one (wrapped angles), plain subtraction otherwise.
/// A model with a difference but no Jacobians cannot be used in a factor (compile error).
template <class Model>
Vector<Model::dim> difference(const Model& m, const Vector<Model::dim>& a, const Vector<Model::dim>& b,
                              SquareMatrix<Model::dim>* Ja, SquareMatrix<Model::dim>* Jb) {
  constexpr int N = Model::dim;
  if constexpr (requires { m.difference(a, b, Ja, Jb); }) {
    return m.difference(a, b, Ja, Jb);
  } else {
    static_assert(!requires { m.difference(a, b); },
                  "the model has its own difference(a, b): give it difference(a, b, Ja, Jb) too");
    if (Ja) Ja->setIdentity();
    if (Jb) *Jb = -SquareMatrix<N>::Identity();
    return a - b;
  }
}

/// The same on any scalar (no Jacobians): what the templated residuals use.
template <class Model, class T>
Vector<Model::dim, T> difference(const Model& m, const Vector<Model::dim, T>& a, const Vector<Model::dim, T>& b) {
  if constexpr (requires { m.template difference<T>(a, b); })
    return m.template difference<T>(a, b);
  else
    return a - b;
}

/// Gaussian prior on one slot: r = W (x - mean), W' W = the information. The
/// marginalisation of a window's oldest state produces one of these on the next.
template <int N>
struct PriorFactor {
  static constexpr int dim = N;
  static constexpr std::array<int, 1> slot_dims{N};
  Vector<N> mean = Vector<N>::Zero();
  SquareMatrix<N> W = SquareMatrix<N>::Identity();

  Vector<N> evaluate(const Vector<N>& x, Matrix<N, N>* J = nullptr) const {
    if (J) *J = W;
    return W * (x - mean);
  }
  template <class T>
  Vector<N, T> residual(const Vector<N, T>& x) const {
    return W.template cast<T>() * (x - mean.template cast<T>());
  }
};

template <int N>
Status make_prior_factor(const Gaussian<N>& g, PriorFactor<N>& out) {
  if (!all_finite(g.mean)) return Status::invalid(Problem::non_finite_state);
  PriorFactor<N> f;
  f.mean = g.mean;
  if (Problem p = whitening_from_covariance<N>(g.cov, f.W); p != Problem::none) return Status::invalid(p);
  out = f;
  return Status{};
}

}  // namespace ctxfuse

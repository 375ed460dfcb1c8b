// What the filters ask of models. Models are plain structs: data (noise figures, lever arms,
// anchor positions) plus const member functions; no base classes, no virtual calls.
//
// Process model M:
//   using State = ...;       // Vector<dim> for an EKF; any type (quaternions, ...) for an ESKF
//   using Input = ...;       // NoInput, an Eigen vector, or a struct with is_finite()
//   static constexpr int dim;                       // (error-)state dimension
//   State predict(const State&, const Input&, double dt, SquareMatrix<dim>* F) const;
//   SquareMatrix<dim> noise(const State&, const Input&, double dt) const;   // discrete Q
// The Jacobian is written only when F is not null, so callers that do not need it (sigma
// points, simulation, numerical differentiation) do not pay for it.
// Error-state models add the retraction and its inverse:
//   State inject(const State&, const Vector<dim>& dx) const;      // x [+] dx
//   Vector<dim> difference(const State& a, const State& b) const; // a [-] b
// and optionally `SquareMatrix<dim> reset_jacobian(const State&, const Vector<dim>& dx)`.
//
// Measurement model H over a state type X with error dimension N:
//   static constexpr int dim;                                     // measurement dimension
//   Vector<dim> predict(const X&, Matrix<dim, N>* H) const;
//   SquareMatrix<dim> noise(const X&) const;                      // R
//   optional: Vector<dim> residual(const Vector<dim>& z, const Vector<dim>& z_pred) const;
//   optional: Problem check(const Vector<dim>& z) const;          // model-specific validation
#pragma once

#include <concepts>
#include <type_traits>

#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse {

template <class M>
concept ProcessModel =
    requires {
      typename M::State;
      typename M::Input;
      { M::dim } -> std::convertible_to<int>;
    } &&
    requires(const M& m, const typename M::State& x, const typename M::Input& u, double dt,
             SquareMatrix<M::dim>* F) {
      { m.predict(x, u, dt, F) } -> std::convertible_to<typename M::State>;
      { m.noise(x, u, dt) } -> std::convertible_to<SquareMatrix<M::dim>>;
    };

/// A process model whose state is a plain vector: what a (linear or extended) Kalman filter takes.
template <class M>
concept VectorProcessModel = ProcessModel<M> && std::same_as<typename M::State, Vector<M::dim>>;

/// A process model with a retraction: what the error-state filter takes.
template <class M>
concept ErrorStateProcessModel =
    ProcessModel<M> && requires(const M& m, const typename M::State& x, const Vector<M::dim>& dx) {
      { m.inject(x, dx) } -> std::convertible_to<typename M::State>;
      { m.difference(x, x) } -> std::convertible_to<Vector<M::dim>>;
    };

template <class H, class X, int N>
concept MeasurementModel =
    requires {
      { H::dim } -> std::convertible_to<int>;
    } && requires(const H& h, const X& x, Matrix<H::dim, N>* J) {
      { h.predict(x, J) } -> std::convertible_to<Vector<H::dim>>;
      { h.noise(x) } -> std::convertible_to<SquareMatrix<H::dim>>;
    };

template <class G>
concept GatePolicy = requires(const G& g, int dof) {
  { g.threshold(dof) } -> std::convertible_to<double>;
};

}  // namespace ctxfuse

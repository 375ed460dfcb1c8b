// Factors from the filters' models (the factor contract is in core/factor.hpp): a measurement
// model gives the unary factor h(x) - z, a process model the binary x_{k+1} [-] f(x_k, u).
// They validate their inputs exactly as the EKF steps do (same checks, same Problems), so a
// measurement the EKF refuses is refused by the smoother too. Models provide `value<T>`
// (models/kinematic.hpp) for the templated path; `predict(x, &J)` stays the analytic one.
#pragma once

#include "ctxfuse/core/concepts.hpp"
#include "ctxfuse/core/factor.hpp"
#include "ctxfuse/core/validation.hpp"
#include "ctxfuse/filters/kalman_update.hpp"

namespace ctxfuse {

/// Unary factor of a measurement model over an N-vector state: r = W (h(x) - z), with W
/// from the model's noise R at the point the factor was made (R of a range does not depend
/// on the state; a model whose R does is linearised there, as an EKF would).
template <int N, class Meas>
struct MeasurementFactor {
  using Model = Meas;
  static constexpr int dim = Meas::dim;
  static constexpr std::array<int, 1> slot_dims{N};
  Meas model{};
  Vector<dim> z = Vector<dim>::Zero();
  SquareMatrix<dim> W = SquareMatrix<dim>::Identity();

  Vector<dim> evaluate(const Vector<N>& x, Matrix<dim, N>* J = nullptr) const {
    Matrix<dim, N> H;
    const Vector<dim> z_pred = model.predict(x, J ? &H : nullptr);
    if (J) J->noalias() = W * H;
    // The model's own residual (angle wrapping) when it has one: innovation() is z - h(x).
    return -(W * detail::innovation(model, z, z_pred));
  }
  template <class T>
  Vector<dim, T> residual(const Vector<N, T>& x) const {
    return W.template cast<T>() * (model.template value<T>(x) - z.template cast<T>());
  }
};

/// Checks z and R as an EKF update does (filters/ekf.hpp), then whitens.
template <int N, class Meas>
  requires MeasurementModel<Meas, Vector<N>, N>
Status make_measurement_factor(const Meas& meas, const Vector<Meas::dim>& z, const Vector<N>& x_lin,
                               MeasurementFactor<N, Meas>& out, const FilterOptions& opts = {}) {
  const SquareMatrix<Meas::dim> R = meas.noise(x_lin);
  if (Problem p = check_measurement<Meas::dim>(z, R, opts); p != Problem::none) return Status::invalid(p);
  if (Problem p = detail::model_check(meas, z); p != Problem::none) return Status::invalid(p);
  MeasurementFactor<N, Meas> f{meas, z, SquareMatrix<Meas::dim>::Identity()};
  if (Problem p = whitening_from_covariance<Meas::dim>(R, f.W); p != Problem::none) return Status::invalid(p);
  out = f;
  return Status{};
}
/// z of a size known only at run time: refused with measurement_wrong_size unless Meas::dim x 1.
template <int N, class Meas, DynamicSizeEigen Z>
  requires MeasurementModel<Meas, Vector<N>, N>
Status make_measurement_factor(const Meas& meas, const Z& z, const Vector<N>& x_lin, MeasurementFactor<N, Meas>& out,
                               const FilterOptions& opts = {}) {
  return with_size_checked<Vector<Meas::dim>>(z, Problem::measurement_wrong_size, [&](const Vector<Meas::dim>& f) {
    return make_measurement_factor<N>(meas, f, x_lin, out, opts);
  });
}

/// Binary factor of a process model between consecutive states: r = W (x_{k+1} [-] f(x_k, u, dt)),
/// W from the discrete process noise Q, which must be positive definite (white acceleration
/// noise on p and v is, for any dt > 0; a model with a noise-free block cannot be a soft factor).
template <VectorProcessModel Model>
struct MotionFactor {
  static constexpr int dim = Model::dim;
  static constexpr std::array<int, 2> slot_dims{Model::dim, Model::dim};
  Model model{};
  typename Model::Input input{};
  double dt = 0.0;
  SquareMatrix<dim> W = SquareMatrix<dim>::Identity();

  Vector<dim> evaluate(const Vector<dim>& x0, const Vector<dim>& x1, SquareMatrix<dim>* J0 = nullptr,
                       SquareMatrix<dim>* J1 = nullptr) const {
    SquareMatrix<dim> F, D_pred, D_next;
    const Vector<dim> pred = model.predict(x0, input, dt, J0 ? &F : nullptr);
    if constexpr (!requires { model.difference(x1, pred, &D_next, &D_pred); }) {
      // Plain subtraction: d/dx1 = I, d/dpred = -I; skip the products with identities.
      if (J0) J0->noalias() = -W.lazyProduct(F);
      if (J1) *J1 = W;
      return W * (x1 - pred);
    }
    const bool need = J0 || J1;
    const Vector<dim> d = difference(model, x1, pred, need ? &D_next : nullptr, need ? &D_pred : nullptr);
    if (J0) J0->noalias() = W * (D_pred * F);
    if (J1) J1->noalias() = W * D_next;
    return W * d;
  }
  /// x1 - f(x0) before whitening (r = W times it), and f's Jacobian at x0 when F is given:
  /// what AffineFactorBlocks and WhitenedInformation work from. Only for a model without its
  /// own difference.
  Vector<dim> unwhitened(const Vector<dim>& x0, const Vector<dim>& x1, SquareMatrix<dim>* F = nullptr) const
    requires(!requires(const Vector<dim>& a, SquareMatrix<dim>* J) { model.difference(a, a, J, J); })
  {
    return x1 - model.predict(x0, input, dt, F);
  }
  template <class T>
  Vector<dim, T> residual(const Vector<dim, T>& x0, const Vector<dim, T>& x1) const {
    const Vector<dim, T> pred = model.template value<T>(x0, input, dt);
    return W.template cast<T>() * difference<Model, T>(model, x1, pred);
  }
};

/// A process model that declares (`static constexpr bool affine_in_state = true`) that
/// f(x, u, dt) = F(u, dt) x + b(u, dt) with F independent of x, and whose difference is plain
/// subtraction: its motion factor's Jacobians are then constants of the factor, and a solver
/// may form their J'J blocks once (AffineFactorBlocks) instead of at every linearisation.
/// tests/factors/factor_jacobian_test.cpp checks the declaration of each model that makes it.
template <class M>
concept AffineProcessModel =
    VectorProcessModel<M> && requires { requires M::affine_in_state; } &&
    !requires(const M& m, const Vector<M::dim>& a, SquareMatrix<M::dim>* J) { m.difference(a, a, J, J); };

/// Checks dt, the input and Q as an EKF prediction does, then whitens with Q at x_lin.
template <VectorProcessModel Model>
Status make_motion_factor(const Model& model, const typename Model::Input& u, double dt, const Vector<Model::dim>& x_lin,
                          MotionFactor<Model>& out, const FilterOptions& opts = {}) {
  if (Problem p = check_dt(dt, opts); p != Problem::none) return Status::invalid(p);
  if (Problem p = check_input(u, opts); p != Problem::none) return Status::invalid(p);
  if (Problem p = detail::model_input_check(model, u); p != Problem::none) return Status::invalid(p);
  const SquareMatrix<Model::dim> Q = model.noise(x_lin, u, dt);
  if (!all_finite(Q)) return Status::invalid(Problem::process_noise_non_finite);
  if (Problem p = check_process_noise(Q); p != Problem::none) return Status::invalid(p);
  MotionFactor<Model> f{model, u, dt, SquareMatrix<Model::dim>::Identity()};
  if (whitening_from_covariance<Model::dim>(Q, f.W) != Problem::none)
    return Status::invalid(Problem::process_noise_negative_variance);
  out = f;
  return Status{};
}
/// u of a size known only at run time: refused with input_wrong_size unless it is Model::Input's.
template <VectorProcessModel Model, DynamicSizeEigen U>
  requires FixedSizeEigen<typename Model::Input>
Status make_motion_factor(const Model& model, const U& u, double dt, const Vector<Model::dim>& x_lin,
                          MotionFactor<Model>& out, const FilterOptions& opts = {}) {
  using In = typename Model::Input;
  return with_size_checked<In>(u, Problem::input_wrong_size,
                               [&](const In& f) { return make_motion_factor(model, f, dt, x_lin, out, opts); });
}

}  // namespace ctxfuse

// Error-state extended Kalman filter. The nominal state may be any type (a quaternion
// attitude, a manifold) with a model-supplied retraction `inject` (x [+] dx) and its inverse
// `difference`; the filter carries the covariance of the error around the nominal. After a
// correction dx is injected, the error is reset to zero and the covariance is mapped through
// the model's reset Jacobian G = d(new error)/d(old error), when the model provides one.
#pragma once

#include "ctxfuse/core/concepts.hpp"
#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/core/validation.hpp"
#include "ctxfuse/filters/filter_clock.hpp"
#include "ctxfuse/filters/kalman_update.hpp"
#include "ctxfuse/filters/stateful_filter.hpp"
#include "ctxfuse/policies/gating.hpp"

namespace ctxfuse::eskf {

template <ErrorStateProcessModel Model>
using Belief = ErrorStateBelief<typename Model::State, Model::dim>;

namespace detail {
// A nominal state is finite when the model says so, or else when its difference from itself
// is (NaN propagates through any retraction's inverse).
template <class Model>
bool nominal_is_finite(const Model& model, const typename Model::State& x) {
  if constexpr (requires { { model.is_finite(x) } -> std::convertible_to<bool>; })
    return model.is_finite(x);
  else
    return all_finite(model.difference(x, x));
}
}  // namespace detail

namespace detail {
/// Every check and the whole prediction, written only to `nominal` and to the LOWER triangle
/// of `cov_lower` (its strict upper triangle is left unspecified). Both hold the prediction
/// only when the status is accepted; nothing of `in` is written, and `nominal` and
/// `cov_lower` may not alias it.
template <ErrorStateProcessModel Model>
Status predict_lower(const Model& model, const Belief<Model>& in, typename Model::State& nominal,
                     SquareMatrix<Model::dim>& cov_lower, const typename Model::Input& u, double dt,
                     const FilterOptions& opts, SquareMatrix<Model::dim>* F_used) {
  constexpr int N = Model::dim;
  if (Problem p = check_dt(dt, opts); p != Problem::none) return Status::invalid(p);
  if (Problem p = check_input(u, opts); p != Problem::none) return Status::invalid(p);
  if (Problem p = ctxfuse::detail::model_input_check(model, u); p != Problem::none) return Status::invalid(p);

  const SquareMatrix<N> Q = model.noise(in.nominal, u, dt);
  if (Problem p = check_process_noise(Q); p != Problem::none) return Status::invalid(p);

  SquareMatrix<N> F;
  nominal = model.predict(in.nominal, u, dt, &F);
  if (!nominal_is_finite(model, nominal)) return Status::failure(Problem::non_finite_prediction);
  // Lower triangle of F P F' + Q.
  ctxfuse::detail::propagate_covariance_lower<Model>(F, in.cov, cov_lower);
  if (!ctxfuse::detail::add_lower_all_finite(cov_lower, Q)) {
    const Problem p = diagnose_non_finite_prediction(Q, F);
    return p == Problem::process_noise_non_finite ? Status::invalid(p) : Status::failure(p);
  }
  if (F_used) *F_used = F;
  return Status{};
}

/// The prediction from `in` into `out`, which may not alias `in`; `out` is scratch that holds
/// the predicted belief only when the status is accepted (an IMM predicts all its modes this
/// way and commits them together).
template <ErrorStateProcessModel Model>
Status predict_into(const Model& model, const Belief<Model>& in, Belief<Model>& out, const typename Model::Input& u,
                    double dt, const FilterOptions& opts, SquareMatrix<Model::dim>* F_used) {
  const Status s = predict_lower(model, in, out.nominal, out.cov, u, dt, opts, F_used);
  if (s.accepted()) symmetrize(out.cov);
  return s;
}
}  // namespace detail

/// Nominal propagation and error covariance prediction P+ = F P F' + Q. Everything that can
/// fail is computed into locals (the nominal and the lower triangle of P+, neither
/// initialised first); the belief is written only once all of it has succeeded: the nominal,
/// then the lower triangle, mirrored onto the upper one.
template <ErrorStateProcessModel Model>
Status predict(const Model& model, Belief<Model>& belief, const typename Model::Input& u, double dt,
               const FilterOptions& opts = {}, SquareMatrix<Model::dim>* F_used = nullptr) {
  typename Model::State nominal;
  SquareMatrix<Model::dim> cov_lower;
  const Status s = detail::predict_lower(model, belief, nominal, cov_lower, u, dt, opts, F_used);
  if (s.accepted()) {
    belief.nominal = nominal;
    ctxfuse::detail::assign_lower_mirrored(cov_lower, belief.cov);
  }
  return s;
}

namespace detail {
/// The correction, injection and reset from `in` into `out`, which may not alias `in`; `out`
/// is scratch that holds the corrected belief only when the status is accepted (an IMM
/// corrects its modes this way and swaps buffers instead of copying covariances).
template <ErrorStateProcessModel Model, class Meas, class Gate>
  requires MeasurementModel<Meas, typename Model::State, Model::dim> && GatePolicy<Gate>
Status update_into(const Model& model, const Meas& meas, const Belief<Model>& in, Belief<Model>& out,
                   const Vector<Meas::dim>& z, const Gate& gate, const FilterOptions& opts,
                   Vector<Model::dim>* dx_applied) {
  constexpr int N = Model::dim;
  constexpr int M = Meas::dim;
  const SquareMatrix<M> R = meas.noise(in.nominal);
  if (Problem p = check_measurement<M>(z, R, opts); p != Problem::none) return Status::invalid(p);
  if (Problem p = ctxfuse::detail::model_check(meas, z); p != Problem::none) return Status::invalid(p);

  Matrix<M, N> H;
  const Vector<M> z_pred = meas.predict(in.nominal, &H);
  const Vector<M> y = ctxfuse::detail::innovation(meas, z, z_pred);

  Vector<N> dx;
  Status status = ctxfuse::detail::kalman_correction<Meas, N, M>(in.cov, H, y, R, gate, dx, out.cov);
  if (!status.accepted()) return status;

  out.nominal = model.inject(in.nominal, dx);
  if (!detail::nominal_is_finite(model, out.nominal)) return Status::failure(Problem::non_finite_state);
  if constexpr (requires { { model.reset_jacobian(in.nominal, dx) } -> std::convertible_to<SquareMatrix<N>>; }) {
    const SquareMatrix<N> G = model.reset_jacobian(in.nominal, dx);
    ctxfuse::detail::reset_covariance_lower_in_place<Model>(G, out.cov);
  }
  if (!ctxfuse::detail::finish_covariance(out.cov)) return Status::failure(Problem::non_finite_covariance);
  if (dx_applied) *dx_applied = dx;
  return status;
}
}  // namespace detail

/// Correction, injection and reset. `dx_applied`, when given, receives the injected error.
/// The belief is written only once everything has succeeded.
template <ErrorStateProcessModel Model, class Meas, class Gate = policies::NoGate>
  requires MeasurementModel<Meas, typename Model::State, Model::dim> && GatePolicy<Gate>
Status update(const Model& model, const Meas& meas, Belief<Model>& belief, const Vector<Meas::dim>& z,
              const Gate& gate = {}, const FilterOptions& opts = {}, Vector<Model::dim>* dx_applied = nullptr) {
  Belief<Model> next;
  const Status status = detail::update_into(model, meas, belief, next, z, gate, opts, dx_applied);
  if (status.accepted()) belief = next;
  return status;
}

// Arguments whose size is known only at run time (VectorXd, Map, dynamic blocks): the size is
// checked before anything is read, and a wrong one is refused (core/validation.hpp).
template <ErrorStateProcessModel Model, DynamicSizeEigen U>
  requires FixedSizeEigen<typename Model::Input>
Status predict(const Model& model, Belief<Model>& belief, const U& u, double dt, const FilterOptions& opts = {},
               SquareMatrix<Model::dim>* F_used = nullptr) {
  using In = typename Model::Input;
  return with_size_checked<In>(u, Problem::input_wrong_size,
                               [&](const In& f) { return predict(model, belief, f, dt, opts, F_used); });
}
template <ErrorStateProcessModel Model, class Meas, DynamicSizeEigen Z, class Gate = policies::NoGate>
  requires MeasurementModel<Meas, typename Model::State, Model::dim> && GatePolicy<Gate>
Status update(const Model& model, const Meas& meas, Belief<Model>& belief, const Z& z, const Gate& gate = {},
              const FilterOptions& opts = {}, Vector<Model::dim>* dx_applied = nullptr) {
  return with_size_checked<Vector<Meas::dim>>(z, Problem::measurement_wrong_size, [&](const Vector<Meas::dim>& f) {
    return update(model, meas, belief, f, gate, opts, dx_applied);
  });
}

}  // namespace ctxfuse::eskf

namespace ctxfuse {

struct EskfSteps {
  template <class Model, class Belief, class Input>
  static Status predict(const Model& m, Belief& b, const Input& u, double dt, const FilterOptions& o) {
    return eskf::predict(m, b, u, dt, o);
  }
  template <class Model, class Meas, class Belief, class Gate>
  static Status update(const Model& m, const Meas& h, Belief& b, const Vector<Meas::dim>& z, const Gate& g,
                       const FilterOptions& o) {
    return eskf::update(m, h, b, z, g, o);
  }
};

/// Stateful error-state EKF: belief + clock + gate around the eskf:: steps.
template <ErrorStateProcessModel Model, GatePolicy Gate = policies::NoGate>
class Eskf : public detail::StatefulFilter<Model, Gate, eskf::Belief<Model>, EskfSteps> {
  using Base = detail::StatefulFilter<Model, Gate, eskf::Belief<Model>, EskfSteps>;

 public:
  using State = typename Model::State;
  using Base::Base;
  const State& nominal() const { return this->belief().nominal; }
};

}  // namespace ctxfuse

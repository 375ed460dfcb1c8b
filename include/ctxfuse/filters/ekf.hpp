// Kalman filter / extended Kalman filter over a vector state.
//
// The steps are free functions over a Gaussian (stateless, as in vortex-vkf): they validate
// every input, compute the new belief into locals and assign it only when the status is
// accepted, so a rejected step leaves the caller's belief bit-for-bit unchanged. The Ekf class
// wraps them with a belief, a clock and the gate. Linear models are the special case whose
// predict/Jacobian are constant matrices.
#pragma once

#include "ctxfuse/core/concepts.hpp"
#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/core/validation.hpp"
#include "ctxfuse/filters/filter_clock.hpp"
#include "ctxfuse/filters/kalman_update.hpp"
#include "ctxfuse/filters/stateful_filter.hpp"
#include "ctxfuse/policies/gating.hpp"

namespace ctxfuse::ekf {

/// x+ = f(x, u, dt), P+ = F P F' + Q. `F_used`, when given, receives the Jacobian (for
/// smoothers) -- only on acceptance.
template <VectorProcessModel Model>
Status predict(const Model& model, Gaussian<Model::dim>& belief, const typename Model::Input& u, double dt,
               const FilterOptions& opts = {}, SquareMatrix<Model::dim>* F_used = nullptr) {
  constexpr int N = Model::dim;
  if (Problem p = check_dt(dt, opts); p != Problem::none) return Status::invalid(p);
  if (Problem p = check_input(u, opts); p != Problem::none) return Status::invalid(p);
  if (Problem p = detail::model_input_check(model, u); p != Problem::none) return Status::invalid(p);
  if (!all_finite(belief.mean)) return Status::invalid(Problem::non_finite_prior);

  const SquareMatrix<N> Q = model.noise(belief.mean, u, dt);
  if (Problem p = check_process_noise(Q); p != Problem::none) return Status::invalid(p);

  SquareMatrix<N> F;
  const Vector<N> x = model.predict(belief.mean, u, dt, &F);
  if (!all_finite(x)) return Status::failure(Problem::non_finite_prediction);
  SquareMatrix<N> P = ctxfuse::detail::propagate_covariance<Model>(F, belief.cov);
  P += Q;
  if (!all_finite(P)) {
    const Problem p = diagnose_non_finite_prediction(Q, F);
    return p == Problem::process_noise_non_finite ? Status::invalid(p) : Status::failure(p);
  }
  symmetrize(P);

  belief.mean = x;
  belief.cov = P;
  if (F_used) *F_used = F;
  return Status{};
}

/// Measurement update with gating. x+ = x + K (z - h(x)), Joseph-form covariance.
template <int N, class Meas, class Gate = policies::NoGate>
  requires MeasurementModel<Meas, Vector<N>, N> && GatePolicy<Gate>
Status update(const Meas& meas, Gaussian<N>& belief, const Vector<Meas::dim>& z, const Gate& gate = {},
              const FilterOptions& opts = {}) {
  constexpr int M = Meas::dim;
  const SquareMatrix<M> R = meas.noise(belief.mean);
  if (Problem p = check_measurement<M>(z, R, opts); p != Problem::none) return Status::invalid(p);
  if (Problem p = detail::model_check(meas, z); p != Problem::none) return Status::invalid(p);
  // The posterior covariance is checked after the correction, which catches a NaN anywhere in
  // the prior's; a NaN in a component of the mean that the measurement does not see would
  // otherwise pass through an accepted update.
  if (!all_finite(belief.mean)) return Status::invalid(Problem::non_finite_prior);

  Matrix<M, N> H;
  const Vector<M> z_pred = meas.predict(belief.mean, &H);
  const Vector<M> y = detail::innovation(meas, z, z_pred);

  Vector<N> dx;
  SquareMatrix<N> P;
  Status status = detail::kalman_correction<Meas, N, M>(belief.cov, H, y, R, gate, dx, P);
  if (!status.accepted()) return status;
  if (!detail::finish_covariance(P)) return Status::failure(Problem::non_finite_covariance);
  const Vector<N> x = belief.mean + dx;  // finite terms can still overflow near 1e308
  if (!all_finite(x)) return Status::failure(Problem::non_finite_state);
  belief.mean = x;
  belief.cov = P;
  return status;
}

// Arguments whose size is known only at run time (VectorXd, Map, dynamic blocks): the size is
// checked before anything is read, and a wrong one is refused (core/validation.hpp).
template <VectorProcessModel Model, DynamicSizeEigen U>
  requires FixedSizeEigen<typename Model::Input>
Status predict(const Model& model, Gaussian<Model::dim>& belief, const U& u, double dt, const FilterOptions& opts = {},
               SquareMatrix<Model::dim>* F_used = nullptr) {
  using In = typename Model::Input;
  return with_size_checked<In>(u, Problem::input_wrong_size,
                               [&](const In& f) { return predict(model, belief, f, dt, opts, F_used); });
}
template <int N, class Meas, DynamicSizeEigen Z, class Gate = policies::NoGate>
  requires MeasurementModel<Meas, Vector<N>, N> && GatePolicy<Gate>
Status update(const Meas& meas, Gaussian<N>& belief, const Z& z, const Gate& gate = {}, const FilterOptions& opts = {}) {
  return with_size_checked<Vector<Meas::dim>>(z, Problem::measurement_wrong_size, [&](const Vector<Meas::dim>& f) {
    return update<N>(meas, belief, f, gate, opts);
  });
}

}  // namespace ctxfuse::ekf

namespace ctxfuse {

struct EkfSteps {
  template <class Model, class Belief, class Input>
  static Status predict(const Model& m, Belief& b, const Input& u, double dt, const FilterOptions& o) {
    return ekf::predict(m, b, u, dt, o);
  }
  template <class Model, class Meas, class Belief, class Gate>
  static Status update(const Model&, const Meas& h, Belief& b, const Vector<Meas::dim>& z, const Gate& g,
                       const FilterOptions& o) {
    return ekf::update<Model::dim>(h, b, z, g, o);
  }
};

/// Stateful EKF: belief + clock + gate around the ekf:: steps.
template <VectorProcessModel Model, GatePolicy Gate = policies::NoGate>
class Ekf : public detail::StatefulFilter<Model, Gate, Gaussian<Model::dim>, EkfSteps> {
  using Base = detail::StatefulFilter<Model, Gate, Gaussian<Model::dim>, EkfSteps>;

 public:
  using Base::Base;
};

}  // namespace ctxfuse

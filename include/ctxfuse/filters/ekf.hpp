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
template <int N, class Meas, class Gate = NoGate>
  requires MeasurementModel<Meas, Vector<N>, N> && GatePolicy<Gate>
Status update(const Meas& meas, Gaussian<N>& belief, const Vector<Meas::dim>& z, const Gate& gate = {},
              const FilterOptions& opts = {}) {
  constexpr int M = Meas::dim;
  const SquareMatrix<M> R = meas.noise(belief.mean);
  if (Problem p = check_measurement<M>(z, R, opts); p != Problem::none) return Status::invalid(p);
  if (Problem p = detail::model_check(meas, z); p != Problem::none) return Status::invalid(p);

  Matrix<M, N> H;
  const Vector<M> z_pred = meas.predict(belief.mean, &H);
  const Vector<M> y = detail::innovation(meas, z, z_pred);

  Vector<N> dx;
  SquareMatrix<N> P;
  Status status = detail::kalman_correction<Meas, N, M>(belief.cov, H, y, R, gate, dx, P);
  if (!status.accepted()) return status;
  if (!detail::finish_covariance(P)) return Status::failure(Problem::non_finite_covariance);
  belief.mean += dx;
  belief.cov = P;
  return status;
}

}  // namespace ctxfuse::ekf

namespace ctxfuse {

/// Stateful EKF: belief + clock + gate around the ekf:: steps.
template <VectorProcessModel Model, GatePolicy Gate = NoGate>
class Ekf {
 public:
  static constexpr int dim = Model::dim;
  using Input = typename Model::Input;
  using Belief = Gaussian<dim>;

  Ekf(Model model, Belief initial, FilterOptions options = {}, Gate gate = {})
      : model_(std::move(model)), belief_(std::move(initial)), options_(options), gate_(std::move(gate)) {}

  const Belief& belief() const { return belief_; }
  const Model& model() const { return model_; }
  const Gate& gate() const { return gate_; }
  const FilterOptions& options() const { return options_; }
  double time() const { return clock_.time(); }
  void set_time(double t) { clock_.set(t); }
  void reset(const Belief& b) { belief_ = b; }

  Status predict(const Input& u, double dt) { return ekf::predict(model_, belief_, u, dt, options_); }

  /// Predict from the filter time to `t`; out-of-order or unset time is rejected.
  Status predict_to(double t, const Input& u) {
    double dt = 0.0;
    if (Problem p = clock_.dt_to(t, dt); p != Problem::none) return Status::invalid(p);
    Status s = predict(u, dt);
    if (s) clock_.set(t);
    return s;
  }

  template <class Meas>
  Status update(const Meas& meas, const Vector<Meas::dim>& z) {
    return ekf::update<dim>(meas, belief_, z, gate_, options_);
  }

 private:
  Model model_;
  Belief belief_;
  FilterOptions options_;
  Gate gate_;
  FilterClock clock_;
};

}  // namespace ctxfuse

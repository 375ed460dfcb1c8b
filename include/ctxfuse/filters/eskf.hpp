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

/// Nominal propagation and error covariance prediction P+ = F P F' + Q.
template <ErrorStateProcessModel Model>
Status predict(const Model& model, Belief<Model>& belief, const typename Model::Input& u, double dt,
               const FilterOptions& opts = {}, SquareMatrix<Model::dim>* F_used = nullptr) {
  constexpr int N = Model::dim;
  if (Problem p = check_dt(dt, opts); p != Problem::none) return Status::invalid(p);
  if (Problem p = check_input(u, opts); p != Problem::none) return Status::invalid(p);
  if (Problem p = ctxfuse::detail::model_input_check(model, u); p != Problem::none) return Status::invalid(p);

  const SquareMatrix<N> Q = model.noise(belief.nominal, u, dt);
  if (Problem p = check_process_noise(Q); p != Problem::none) return Status::invalid(p);

  SquareMatrix<N> F;
  typename Model::State x = model.predict(belief.nominal, u, dt, &F);
  if (!detail::nominal_is_finite(model, x)) return Status::failure(Problem::non_finite_prediction);
  SquareMatrix<N> P = ctxfuse::detail::propagate_covariance<Model>(F, belief.cov);
  P += Q;
  if (!all_finite(P)) {
    const Problem p = diagnose_non_finite_prediction(Q, F);
    return p == Problem::process_noise_non_finite ? Status::invalid(p) : Status::failure(p);
  }
  symmetrize(P);

  belief.nominal = std::move(x);
  belief.cov = P;
  if (F_used) *F_used = F;
  return Status{};
}

/// Correction, injection and reset. `dx_applied`, when given, receives the injected error.
template <ErrorStateProcessModel Model, class Meas, class Gate = NoGate>
  requires MeasurementModel<Meas, typename Model::State, Model::dim> && GatePolicy<Gate>
Status update(const Model& model, const Meas& meas, Belief<Model>& belief, const Vector<Meas::dim>& z,
              const Gate& gate = {}, const FilterOptions& opts = {}, Vector<Model::dim>* dx_applied = nullptr) {
  constexpr int N = Model::dim;
  constexpr int M = Meas::dim;
  const SquareMatrix<M> R = meas.noise(belief.nominal);
  if (Problem p = check_measurement<M>(z, R, opts); p != Problem::none) return Status::invalid(p);
  if (Problem p = ctxfuse::detail::model_check(meas, z); p != Problem::none) return Status::invalid(p);

  Matrix<M, N> H;
  const Vector<M> z_pred = meas.predict(belief.nominal, &H);
  const Vector<M> y = ctxfuse::detail::innovation(meas, z, z_pred);

  Vector<N> dx;
  SquareMatrix<N> P;
  Status status = ctxfuse::detail::kalman_correction<Meas, N, M>(belief.cov, H, y, R, gate, dx, P);
  if (!status.accepted()) return status;

  typename Model::State x = model.inject(belief.nominal, dx);
  if (!detail::nominal_is_finite(model, x)) return Status::failure(Problem::non_finite_state);
  if constexpr (requires { { model.reset_jacobian(belief.nominal, dx) } -> std::convertible_to<SquareMatrix<N>>; }) {
    const SquareMatrix<N> G = model.reset_jacobian(belief.nominal, dx);
    P = ctxfuse::detail::reset_covariance<Model>(G, P);
  }
  if (!ctxfuse::detail::finish_covariance(P)) return Status::failure(Problem::non_finite_covariance);
  belief.nominal = std::move(x);
  belief.cov = P;
  if (dx_applied) *dx_applied = dx;
  return status;
}

}  // namespace ctxfuse::eskf

namespace ctxfuse {

/// Stateful error-state EKF: belief + clock + gate around the eskf:: steps.
template <ErrorStateProcessModel Model, GatePolicy Gate = NoGate>
class Eskf {
 public:
  static constexpr int dim = Model::dim;
  using State = typename Model::State;
  using Input = typename Model::Input;
  using Belief = eskf::Belief<Model>;

  Eskf(Model model, Belief initial, FilterOptions options = {}, Gate gate = {})
      : model_(std::move(model)), belief_(std::move(initial)), options_(options), gate_(std::move(gate)) {}

  const Belief& belief() const { return belief_; }
  const State& nominal() const { return belief_.nominal; }
  const Model& model() const { return model_; }
  const Gate& gate() const { return gate_; }
  const FilterOptions& options() const { return options_; }
  double time() const { return clock_.time(); }
  void set_time(double t) { clock_.set(t); }
  void reset(const Belief& b) { belief_ = b; }

  Status predict(const Input& u, double dt) { return eskf::predict(model_, belief_, u, dt, options_); }

  Status predict_to(double t, const Input& u) {
    double dt = 0.0;
    if (Problem p = clock_.dt_to(t, dt); p != Problem::none) return Status::invalid(p);
    Status s = predict(u, dt);
    if (s) clock_.set(t);
    return s;
  }

  template <class Meas>
  Status update(const Meas& meas, const Vector<Meas::dim>& z) {
    return eskf::update(model_, meas, belief_, z, gate_, options_);
  }

 private:
  Model model_;
  Belief belief_;
  FilterOptions options_;
  Gate gate_;
  FilterClock clock_;
};

}  // namespace ctxfuse

// The fixed-lag smoother (filters/fixed_lag.hpp) as an estimator of the NLOS-robust UWB run
// loop (estimators.hpp for the shape): one window state per epoch, at the epoch's last range
// (the four anchors answer within ~3 ms: at the platform's 3 m/s top speed that is <= 1 cm,
// a tenth of the ranging sigma), a constant-velocity motion factor between states, and the
// epoch's ranges in the state's measurement slots with the policy's mask.
//
// The innovation gate is applied before the solve, range by range, against the motion model's
// prediction of the new state (mean F x, covariance F P F' + Q from the newest state's marginal
// covariance): the same test the EKF makes, so that a gross range never enters the window.
// OutputLag = 0 reports the newest state (causal, like the EKF); OutputLag = L reports the
// state L epochs back with its own time (a fixed-lag estimate, L / 10 Hz late), which has the
// ranges after it too.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <optional>
#include <span>
#include <type_traits>
#include <utility>

#include "ctxfuse/core/status.hpp"
#include "ctxfuse/filters/fixed_lag.hpp"
#include "ctxfuse/pipelines/nlos_uwb/estimators.hpp"

namespace ctxfuse::pipelines::nlos_uwb {

/// The EKF's checks and NIS test of one range (model h) against a predicted state (x, P):
/// what the smoothers apply before a range enters the window.
template <class Model, int N>
Status gate_range(const Settings& s, double threshold, const Model& h, const messages::UwbRange& r, const Vector<N>& x,
                  const SquareMatrix<N>& P) {
  if (const Problem p = range_problem(r, s); p != Problem::none) return Status::invalid(p);
  Matrix<1, N> H;
  const double y = r.range_m - h.predict(x, &H)(0);
  const double S = (H * P * H.transpose())(0, 0) + h.sigma * h.sigma;
  if (!(S > 0.0) || !std::isfinite(y)) return Status::failure(Problem::innovation_not_positive_definite);
  Status st;
  st.dof = 1;
  st.nis = y * y / S;
  st.gate_threshold = threshold;
  if (!(st.nis <= st.gate_threshold)) st.outcome = Outcome::gated;
  return st;
}

/// What every smoother checks before an epoch: a status to return at once, or none to go on
/// with a step of dt > 0 to the epoch's last range. An epoch whose ranges all share the start's
/// time (a simulator, or a system stamping the epoch once) is the epoch the start's fix was
/// computed from: its ranges are in the prior, and it is accepted without a step.
inline std::optional<Status> smoother_epoch_check(bool started, bool& fresh, double now, int slots,
                                                  std::span<const messages::UwbRange> epoch, std::span<Status> statuses) {
  if (!started) return Status::invalid(Problem::time_not_set);
  if (static_cast<int>(epoch.size()) > slots) return Status::invalid(Problem::measurement_count_above_capacity);
  const double dt = epoch.back().t - now;
  if (std::exchange(fresh, false) && dt == 0.0) {
    for (std::size_t i = 0; i < epoch.size(); ++i) statuses[i] = Status{};
    return Status{};
  }
  if (!(dt > 0.0)) return Status::invalid(dt == 0.0 ? Problem::non_positive_dt : Problem::out_of_order_time);
  return std::nullopt;
}

/// The epoch's attached ranges through the gate against the prediction (x, P), then one step
/// of `smoother` to the epoch's last range with input u; a refused step is every gated-in
/// range's status too. `range(r)` makes the measurement model of range r.
template <class S, class MakeRange>
Status gated_smoother_step(S& smoother, const Settings& s, double gate_threshold, MakeRange&& range,
                           const typename S::Input& u, const Vector<S::dim>& x, const SquareMatrix<S::dim>& P,
                           std::span<const messages::UwbRange> epoch, std::span<const bool> attach, std::span<Status> statuses) {
  typename S::Measurements meas;
  for (std::size_t i = 0; i < epoch.size(); ++i) {
    const auto h = range(epoch[i]);
    bool enter = attach[i];
    if (enter) {
      statuses[i] = gate_range(s, gate_threshold, h, epoch[i], x, P);
      enter = statuses[i].accepted();
    }
    meas.add(h, Vector<1>(epoch[i].range_m), enter);
  }
  const Status st = smoother.step(epoch.back().t, u, meas);
  if (!st.accepted())
    for (std::size_t i = 0; i < epoch.size(); ++i)
      if (attach[i] && statuses[i].accepted()) statuses[i] = st;
  return st;
}

/// The window's state `lag` epochs before the newest (the oldest kept while the window fills).
template <class S>
const auto& lagged_epoch(const S& smoother, int lag) {
  const auto& w = smoother.window();
  return w.epochs[static_cast<std::size_t>(std::max(0, w.size - 1 - lag))];
}

template <int K = 10, GatePolicy Gate = policies::ChiSquareGate, int OutputLag = 0>
class RangeSmoother {
  static_assert(OutputLag >= 0 && OutputLag < K, "the reported state must be in the window");

 public:
  static constexpr int kSlots = 16;  // NlosClassifier::kMaxAnchors: one slot per anchor
  using Motion = models::ConstantVelocity<PlanarLayout, 2>;
  using Smoother = FixedLagSmoother<Motion, RangeAtHeight, K, kSlots>;

  explicit RangeSmoother(const Settings& s) : settings_(s), smoother_(make_motion(s)), gate_(make_gate<Gate>(s)) {}

  bool started() const { return started_; }
  double time() const { return smoother_.time(); }
  Eigen::Vector2d position() const { return smoother_.newest().template head<2>(); }
  Eigen::Vector2d velocity() const { return smoother_.newest().template tail<2>(); }
  void stop() { started_ = false; }

  /// The reported estimate: OutputLag epochs before the newest (the oldest kept while the
  /// window fills).
  double output_time() const { return lagged().time; }
  Eigen::Vector2d output_position() const { return lagged().x.template head<2>(); }

  Status start(double t, const Eigen::Vector2d& p, const Eigen::Matrix2d& P) {
    if (!std::isfinite(t)) return Status::invalid(Problem::non_finite_dt);
    Gaussian<4> prior;
    if (const Status s = initial_belief(p, P, settings_, prior); !s.accepted()) return s;
    const Status s = smoother_.initialise(t, prior);
    started_ = s.accepted();
    fresh_ = started_;
    return s;
  }

  /// The smoother adds states only with an epoch: here only the clock is checked.
  Status predict_to(double t) const { return clock_check(started_, time(), t); }

  Status apply_epoch(std::span<const messages::UwbRange> epoch, std::span<const bool> attach, std::span<Status> statuses) {
    if (auto done = smoother_epoch_check(started_, fresh_, time(), kSlots, epoch, statuses)) return *done;
    const double dt = epoch.back().t - time();
    SquareMatrix<4> F;
    const Vector<4> x = smoother_.motion().predict(smoother_.newest(), NoInput{}, dt, &F);
    const SquareMatrix<4> P = F * smoother_.newest_covariance() * F.transpose() + smoother_.motion().noise(x, NoInput{}, dt);
    auto range = [&](const messages::UwbRange& r) { return RangeAtHeight{r.anchor_position, settings_.tag_height_m, settings_.range_sigma_m}; };
    return gated_smoother_step(smoother_, settings_, gate_.threshold(1), range, NoInput{}, x, P, epoch, attach, statuses);
  }

  const Smoother& smoother() const { return smoother_; }

 private:
  static Motion make_motion(const Settings& s) {
    Motion m;
    m.accel_psd = s.accel_psd;
    return m;
  }

  const typename Smoother::Epoch& lagged() const { return lagged_epoch(smoother_, OutputLag); }

  Settings settings_;
  Smoother smoother_;
  Gate gate_;
  bool started_ = false;
  bool fresh_ = false;  // started, no epoch applied yet
};

}  // namespace ctxfuse::pipelines::nlos_uwb

// The self-calibrating EKF of the gated UWB fusion: the constant-velocity EKF of estimators.hpp
// (RangeEkf) with two things about the ranges that the data shows and RangeEkf leaves out:
//   - a bias per anchor, estimated as a random constant (settings.anchor_bias_sigma_m prior);
//     the anchors of the Hanyang site span 1.9 m x 1.7 m, so a few centimetres of difference
//     between two anchors' biases turn the bearing by about a degree, a metre at 40 m;
//   - the report's time: a range that is the mean of the last n raw ranges is modelled as that
//     mean under constant velocity (models/averaged_range.hpp), not as the range now.
// The estimator keeps the interface of estimators.hpp (the run loop takes it unchanged). On a
// restart (start() after stop() or a lock-out) the position and velocity come from the fix and
// the bias block keeps its mean and covariance: what was learned about the anchors stays.
//
// Lagged = true adds the fixed-lag output (output_time(), output_position(): the run loop emits
// those): the RTS-smoothed position settings.smoothed_output_lag_s behind the newest range
// (filters/fixed_lag_rts.hpp over the current run's records: one per accepted range, one per
// epoch's end).
#pragma once

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <type_traits>

#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/fixed_lag_rts.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/models/averaged_range.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/pipelines/nlos_uwb/estimators.hpp"
#include "ctxfuse/pipelines/nlos_uwb/settings.hpp"
#include "ctxfuse/policies/gating.hpp"

namespace ctxfuse::pipelines::nlos_uwb {

template <int MaxAnchors>
using CalibratedLayout = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>, StateBlock<"b", MaxAnchors>>;

/// MaxAnchors bias slots, taken by anchor id in the order the anchors first range; an anchor
/// beyond them is used without a bias state. The pipeline's runs (studies/nlos_uwb.hpp) take 16,
/// its anchor limit (NlosClassifier::kMaxAnchors): a slot no anchor takes keeps its prior and no
/// correlation, so it changes no estimate (the Hanyang figures are the same to the last digit
/// with 8 and 16). Settings::lag_records sizes the fixed-lag window in records (one per
/// accepted range, one per epoch's end), allocated once at construction: 0.9 s of 4 anchors at
/// 10 Hz is 45; `run uwb` sets it from the recording (recording.hpp, lag_records_needed).
template <GatePolicy Gate = policies::ChiSquareGate, bool Lagged = false, int MaxAnchors = 8>
class CalibratedRangeEkf {
 public:
  static constexpr int N = 4 + MaxAnchors;
  using L = CalibratedLayout<MaxAnchors>;

  explicit CalibratedRangeEkf(const Settings& s) : CalibratedRangeEkf(s, make_gate<Gate>(s)) {}
  CalibratedRangeEkf(const Settings& s, Gate gate) : settings_(s), gate_(gate), lag_(make_lag(s)) {
    motion_.accel_psd = s.accel_psd;
    belief_.mean.setZero();
    belief_.cov.setZero();
    L::template cov<"b">(belief_.cov).diagonal().setConstant(s.anchor_bias_sigma_m * s.anchor_bias_sigma_m);
    slot_ids_.fill(0);
  }

  bool started() const { return started_; }
  double time() const { return t_; }
  Eigen::Vector2d position() const { return L::template get<"p">(belief_.mean); }
  Eigen::Vector2d velocity() const { return L::template get<"v">(belief_.mean); }
  const Gaussian<N>& belief() const { return belief_; }

  /// The bias estimate of an anchor and its sigma; false when the anchor has no slot.
  bool anchor_bias(int anchor_id, double& bias_m, double& sigma_m) const {
    const int k = find_slot(anchor_id);
    if (k < 0) return false;
    bias_m = L::template get<"b">(belief_.mean)(k);
    sigma_m = std::sqrt(L::template cov<"b">(belief_.cov)(k, k));
    return true;
  }

  /// From a snapshot fix: position and covariance from it, velocity within the settings'
  /// speed sigma, the bias block as it was (the prior before the first start).
  Status start(double t, const Eigen::Vector2d& p, const Eigen::Matrix2d& P) {
    if (!std::isfinite(t)) return Status::invalid(Problem::non_finite_dt);
    Gaussian<4> pv;
    if (const Status s = initial_belief(p, P, settings_, pv); !s.accepted()) return s;
    Gaussian<N> b;
    b.mean.setZero();
    b.cov.setZero();
    b.mean.template head<4>() = pv.mean;
    b.cov.template topLeftCorner<4, 4>() = pv.cov;
    L::template get<"b">(b.mean) = L::template get<"b">(belief_.mean);
    L::template cov<"b">(b.cov) = L::template cov<"b">(belief_.cov);
    belief_ = b;
    t_ = t;
    started_ = true;
    if constexpr (Lagged) lag_.start(t, belief_);
    return Status{};
  }

  /// Predicts to t; t equal to the clock is a no-op, t before it is refused (state unchanged).
  Status predict_to(double t) {
    if (const Status c = clock_check(started_, t_, t); !c.accepted() || t == t_) return c;
    SquareMatrix<N> F;
    const Status s = ekf::predict(motion_, belief_, NoInput{}, t - t_, FilterOptions{}, &F);
    if (!s.accepted()) return s;
    t_ = t;
    if constexpr (Lagged) lag_.predicted(F);
    return s;
  }

  /// One range at the clock's time (apply_ranges_in_order predicts to its stamp first).
  Status update(const messages::UwbRange& r) {
    if (!started_) return Status::invalid(Problem::time_not_set);
    if (const Problem p = range_problem(r, settings_); p != Problem::none) return Status::invalid(p);
    models::AveragedRangeWithBias<L> h;
    h.anchor = r.anchor_position;
    h.tag_height = settings_.tag_height_m;
    h.samples = settings_.range_average_samples;
    h.period_s = settings_.range_period_s;
    h.bias_slot = slot_of(r.anchor_id);
    h.sigma = settings_.range_sigma_m;
    if constexpr (Lagged) {
      const Gaussian<N> prior = belief_;
      const Status s = ekf::update<N>(h, belief_, Vector<1>(r.range_m), gate_);
      if (s.accepted()) {
        // Refused only for a prior that is not positive definite, which an accepted update
        // does not have; the window would then start again from this posterior, and the
        // filter's update stands either way.
        (void)lag_.record(t_, prior, belief_);
      }
      return s;
    } else {
      return ekf::update<N>(h, belief_, Vector<1>(r.range_m), gate_);
    }
  }

  Status apply_epoch(std::span<const messages::UwbRange> epoch, std::span<const bool> attach, std::span<Status> statuses) {
    const Status s = apply_ranges_in_order(*this, epoch, attach, statuses);
    if constexpr (Lagged) {
      // The epoch's end is a record too (no update there: prior = posterior), so that the
      // lagged output moves on with every epoch, also with every range left out or gated.
      if (s.accepted()) (void)lag_.record(t_, belief_, belief_);
    }
    return s;
  }

  /// Forgets position and velocity (after a failed step: the next fix starts again); the
  /// anchor biases stay.
  void stop() { started_ = false; }

  double output_time() const
    requires Lagged
  {
    return lagged().t;
  }
  Eigen::Vector2d output_position() const
    requires Lagged
  {
    return L::template get<"p">(lagged().mean);
  }

 private:
  // The backward pass runs once per change of the window, however often the output is asked
  // for (emit asks for time and position).
  const auto& lagged() const
    requires Lagged
  {
    if (lagged_revision_ != lag_.revision()) {
      lagged_ = lag_.smoothed(settings_.smoothed_output_lag_s);
      lagged_revision_ = lag_.revision();
    }
    return lagged_;
  }

  int find_slot(int anchor_id) const {
    for (int k = 0; k < slots_used_; ++k)
      if (slot_ids_[static_cast<std::size_t>(k)] == anchor_id) return k;
    return -1;
  }
  int slot_of(int anchor_id) {
    if (const int k = find_slot(anchor_id); k >= 0) return k;
    if (slots_used_ == MaxAnchors) return -1;
    slot_ids_[static_cast<std::size_t>(slots_used_)] = anchor_id;
    return slots_used_++;
  }

  Settings settings_;
  Gate gate_;
  models::ConstantVelocity<L, 2> motion_;
  Gaussian<N> belief_;
  double t_ = 0.0;
  bool started_ = false;
  std::array<int, MaxAnchors> slot_ids_{};
  int slots_used_ = 0;
  struct NoLag {};
  using Lag = FixedLagRts<N>;
  static auto make_lag(const Settings& s) {
    if constexpr (Lagged) return Lag(s.lag_records); else return NoLag{};
  }
  [[no_unique_address]] std::conditional_t<Lagged, Lag, NoLag> lag_{};
  mutable std::size_t lagged_revision_ = static_cast<std::size_t>(-1);  // lag_'s, when lagged_ was made
  mutable std::conditional_t<Lagged, typename Lag::Smoothed, NoLag> lagged_{};
};

}  // namespace ctxfuse::pipelines::nlos_uwb

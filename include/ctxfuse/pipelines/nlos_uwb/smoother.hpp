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
#include <span>
#include <type_traits>
#include <utility>

#include "ctxfuse/core/status.hpp"
#include "ctxfuse/filters/fixed_lag.hpp"
#include "ctxfuse/pipelines/nlos_uwb/estimators.hpp"

namespace ctxfuse::pipelines::nlos_uwb {

template <int K = 10, GatePolicy Gate = ChiSquareGate, int OutputLag = 0>
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
  Status predict_to(double t) const {
    if (!started_) return Status::invalid(Problem::time_not_set);
    if (!std::isfinite(t)) return Status::invalid(Problem::non_finite_dt);
    return t < time() ? Status::invalid(Problem::out_of_order_time) : Status{};
  }

  Status apply_epoch(std::span<const io::UwbRange> epoch, std::span<const bool> attach, std::span<Status> statuses) {
    if (!started_) return Status::invalid(Problem::time_not_set);
    if (static_cast<int>(epoch.size()) > kSlots) return Status::invalid(Problem::measurement_count_above_capacity);
    const double t = epoch.back().t, dt = t - time();
    // An epoch whose ranges all share the start's time (a simulator, or a system stamping the
    // epoch once) is the epoch the start's fix was computed from: its ranges are in the prior.
    if (std::exchange(fresh_, false) && dt == 0.0) {
      for (std::size_t i = 0; i < epoch.size(); ++i) statuses[i] = Status{};
      return Status{};
    }
    if (!(dt > 0.0)) return Status::invalid(dt == 0.0 ? Problem::non_positive_dt : Problem::out_of_order_time);
    SquareMatrix<4> F;
    const Vector<4> x = smoother_.motion().predict(smoother_.newest(), NoInput{}, dt, &F);
    const SquareMatrix<4> P = F * smoother_.newest_covariance() * F.transpose() + smoother_.motion().noise(x, NoInput{}, dt);
    typename Smoother::Measurements meas;
    for (std::size_t i = 0; i < epoch.size(); ++i) {
      const io::UwbRange& r = epoch[i];
      const RangeAtHeight h{r.anchor_position, settings_.tag_height_m, settings_.range_sigma_m};
      bool enter = attach[i];
      if (enter) {
        statuses[i] = gate(h, r, x, P);
        enter = statuses[i].accepted();
      }
      meas.add(h, Vector<1>(r.range_m), enter);
    }
    const Status s = smoother_.step(t, NoInput{}, meas);
    if (!s.accepted())
      for (std::size_t i = 0; i < epoch.size(); ++i)
        if (attach[i] && statuses[i].accepted()) statuses[i] = s;
    return s;
  }

  const Smoother& smoother() const { return smoother_; }

 private:
  static Motion make_motion(const Settings& s) {
    Motion m;
    m.accel_psd = s.accel_psd;
    return m;
  }

  /// The EKF's checks and NIS test of one range against the predicted state.
  Status gate(const RangeAtHeight& h, const io::UwbRange& r, const Vector<4>& x, const SquareMatrix<4>& P) const {
    if (!r.anchor_position.allFinite() || !std::isfinite(r.range_m)) return Status::invalid(Problem::non_finite_measurement);
    if (!(r.range_m > 0.0 && r.range_m <= settings_.max_range_m)) return Status::invalid(Problem::measurement_out_of_domain);
    Matrix<1, 4> H;
    const double y = r.range_m - h.predict(x, &H)(0);
    const double S = (H * P * H.transpose())(0, 0) + h.sigma * h.sigma;
    if (!(S > 0.0) || !std::isfinite(y)) return Status::failure(Problem::innovation_not_positive_definite);
    Status st;
    st.dof = 1;
    st.nis = y * y / S;
    st.gate_threshold = gate_.threshold(1);
    if (!(st.nis <= st.gate_threshold)) st.outcome = Outcome::gated;
    return st;
  }

  const typename Smoother::Epoch& lagged() const {
    const auto& w = smoother_.window();
    return w.epochs[static_cast<std::size_t>(std::max(0, w.size - 1 - OutputLag))];
  }

  Settings settings_;
  Smoother smoother_;
  Gate gate_;
  bool started_ = false;
  bool fresh_ = false;  // started, no epoch applied yet
};

}  // namespace ctxfuse::pipelines::nlos_uwb

// The EKF of the gated fusion with the IMU as its process model: the same planar IMU state,
// IMU stream, alignment and noise as the IMU smoother (imu_smoother.hpp), one sequential
// range update per attached range at the range's own time, each through the innovation gate.
// It costs one interval prediction and one scalar update per range where the smoother
// re-solves its window; users choose cost against accuracy (docs/results.md nlos_uwb_sim).
//
// The IMU reaches it as pieces (add_imu) that wait in ImuPieces: the run loop hands an epoch
// over only after the epoch's window has closed, by which time the IMU stream has moved past
// its first ranges, so the prediction to each range is made from the buffered pieces on
// demand (interval [time(), t] through models::PlanarImuIntervalModel), not sample by sample.
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <span>

#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/models/planar.hpp"
#include "ctxfuse/models/planar_interval.hpp"
#include "ctxfuse/models/planar_start.hpp"
#include "ctxfuse/pipelines/nlos_uwb/estimators.hpp"
#include "ctxfuse/pipelines/nlos_uwb/imu_smoother.hpp"

namespace ctxfuse::pipelines::nlos_uwb {

template <GatePolicy Gate = policies::ChiSquareGate>
class ImuRangeEkf {
 public:
  static constexpr int kIntervalSamples = 32;
  using L = models::PlanarLayout;
  using Motion = models::PlanarImuIntervalModel<kIntervalSamples>;

  ImuRangeEkf(const Settings& s, const ImuFusionSettings& imu)
      : settings_(s), motion_{imu.model()}, gate_(make_gate<Gate>(s)),
        align_settings_(imu.start(s)), aligner_(align_settings_.alignment_options()) {}

  bool started() const { return started_; }
  double time() const { return t_; }
  Eigen::Vector2d position() const { return L::get<"p">(belief_.mean); }
  Eigen::Vector2d velocity() const { return L::get<"v">(belief_.mean); }
  double heading() const { return belief_.mean(L::offset<"psi">()); }
  const Gaussian<L::size>& belief() const { return belief_; }
  void stop() {
    started_ = false;
    aligner_.reset();
  }

  /// One piece of the IMU stream: sample `s` in force over [t, t + span).
  void add_imu(double t, double span, const messages::ImuSample& s) {
    pieces_.add(t, span, models::planar_input(s), motion_.step);
  }

  /// Offers the fix to the aligner; starts (accepted) at the fix that completes an alignment,
  /// refuses (time_not_set) before.
  Status start(double t, const Eigen::Vector2d& p, const Eigen::Matrix2d& P) {
    if (!std::isfinite(t)) return Status::invalid(Problem::non_finite_dt);
    if (!p.allFinite() || !P.allFinite()) return Status::invalid(Problem::non_finite_measurement);
    const auto al = aligner_.add(t, p, P);
    if (!al) return Status::invalid(Problem::time_not_set);
    belief_ = models::planar_initial_belief(*al, align_settings_);
    t_ = al->t;
    started_ = true;
    pieces_.drop_before(t_);
    return Status{};
  }

  /// Predicts to t over the buffered IMU pieces; t equal to the clock is a no-op, t before it
  /// is refused, and so is an interval that no piece covers (belief and clock unchanged).
  Status predict_to(double t) {
    if (const Status c = clock_check(started_, t_, t); !c.accepted() || t == t_) return c;
    if (!pieces_.interval(t_, t, u_)) return Status::invalid(Problem::non_finite_input);
    if (Problem p = motion_.check(u_, t - t_); p != Problem::none) return Status::invalid(p);
    const Status s = ekf::predict(motion_, belief_, u_, t - t_);
    if (s.accepted()) {
      t_ = t;
      pieces_.drop_before(t_);
    }
    return s;
  }

  Status update(const messages::UwbRange& r) {
    if (!started_) return Status::invalid(Problem::time_not_set);
    if (const Problem p = range_problem(r, settings_); p != Problem::none) return Status::invalid(p);
    return ekf::update<L::size>(planar_range(r, settings_), belief_, Vector<1>(r.range_m), gate_);
  }

  Status apply_epoch(std::span<const messages::UwbRange> epoch, std::span<const bool> attach, std::span<Status> statuses) {
    return apply_ranges_in_order(*this, epoch, attach, statuses);
  }

 private:
  Settings settings_;
  Motion motion_;
  Gate gate_;
  models::PlanarStartSettings align_settings_;  // what the aligner and the initial belief read
  models::DynamicAligner aligner_;
  ImuPieces pieces_;
  typename Motion::Input u_;  // the interval of the latest prediction (kept: no allocation, no large stack copy)
  Gaussian<L::size> belief_;
  double t_ = 0.0;
  bool started_ = false;
};

}  // namespace ctxfuse::pipelines::nlos_uwb

// The single-sensor baselines of the region paper: GNSS alone (the receiver's own fixes) and
// UWB alone (the ranges in a tracker of their own, without the IMU), as a user of either
// system would see it.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <vector>

#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/multilateration.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/pipelines/region_imm/aided.hpp"
#include "ctxfuse/policies/gating.hpp"

namespace ctxfuse::pipelines::region_imm {

/// GNSS alone: the last fix; without a fix at an epoch the receiver's last position is all
/// the user has. A fix whose position is not finite is no fix: the epoch has no solution and
/// the last position is held (before, a NaN fix became the position reported from then on).
struct GnssOnly {
  Track track{};
  Eigen::Vector2d last = Eigen::Vector2d::Zero();
  double last_fix_t = -1e300;
  void start(double, const Gaussian<L::size>& b0) { last = L::get<"p">(b0.mean); }
  void predict(const models::PlanarImu&, double) {}
  void speed(const messages::SpeedSample&) {}
  void uwb(const messages::UwbRange&) {}
  void gnss(const messages::GnssFix& e) {
    if (!e.position.head<2>().allFinite()) return;
    last = e.position.head<2>();
    last_fix_t = e.t;
  }
  void epoch(double t) { track.record(t, last, -1, last_fix_t == t); }
  void start_fix(const messages::GnssFix& e) { gnss(e); }
};

/// UWB alone: the ranges in a constant-velocity EKF (no IMU), as a UWB positioning system
/// runs its own tracker. The track starts from a snapshot multilateration of one epoch's
/// ranges (at least 3 anchors, residuals consistent with line of sight), and is re-anchored
/// to such a snapshot whenever the two disagree (chi-square 0.999 on 2 dof): with only the
/// two approach anchors in reach, ranges cannot tell the track from its mirror image about
/// the anchors' line, and a tracker that once slipped onto the mirror keeps having its
/// ranges accepted there. Lock is lost when no range has arrived for `uwb_hold_after_s` (out
/// of radio range) or when every range has been gated for the health timeout (a lock-out,
/// as policies/health.hpp defines it); without lock the last position is held (what such a
/// system reports when it loses the tag).
template <class = void>
struct UwbOnlyT {
  using Cv = models::ConstantVelocity<L, 2>;
  const Settings& s;
  Track track{};
  std::optional<Ekf<Cv, policies::ChiSquareGate>> f{};
  policies::SourceHealth health{s.health};
  bool locked = false;
  double last_range_t = -1e9;
  Eigen::Vector2d held = Eigen::Vector2d::Zero();
  double now = 0.0;
  std::vector<messages::UwbRange> epoch_ranges{};  // the ranges of the current time stamp so far
  void start(double t0, const Gaussian<L::size>& b0) {
    const Eigen::Vector2d p0 = L::get<"p">(b0.mean);
    Cv cv;
    cv.accel_psd = s.uwb_alone_accel_psd;
    Gaussian<L::size> b;
    b.mean.setZero();
    L::get<"p">(b.mean) = p0;
    b.cov = SquareMatrix<L::size>::Identity();
    f.emplace(cv, b, FilterOptions{}, policies::ChiSquareGate(s.gate_probability));
    now = t0;
    held = p0;
  }
  void predict(const models::PlanarImu&, double dt) {
    now += dt;
    // The constant-velocity model takes no input; dt > 0 is the replay's guarantee.
    (void)f->predict({}, dt);
  }
  void speed(const messages::SpeedSample&) {}
  // The integrity check with the chi-square test (0.999, 2 dof) alone and one snapshot
  // enough: a snapshot tracker has no IMU to carry it through an NLOS stamp, so it follows
  // every snapshot that disagrees.
  policies::SnapshotIntegrity<2> mirror_check{{.probability = 0.999, .min_error_m = 0.0, .consecutive = 1}};
  bool disagrees(const Multilateration& snap, double t) {
    const auto& b = f->belief();
    return mirror_check.check(t, snap.position, snap.cov, L::get<"p">(b.mean), L::cov<"p">(b.cov)).has_value();
  }
  void uwb(const messages::UwbRange& r) {
    last_range_t = now;
    add_to_stamp(epoch_ranges, r);
    const auto snap = multilaterate(epoch_ranges, snapshot_options(s));
    if (snap.ok() && (!locked || disagrees(snap, r.t))) {
      Gaussian<L::size> b = f->belief();
      L::get<"p">(b.mean) = snap.position;
      b.cov = SquareMatrix<L::size>::Identity();
      L::cov<"p">(b.cov) = snap.cov;
      if (!locked) {
        L::get<"v">(b.mean).setZero();
        L::cov<"v">(b.cov) *= 4.0;  // (2 m/s)^2: a vehicle's speed, direction unknown
      } else {
        L::cov<"v">(b.cov) = L::cov<"v">(f->belief().cov);
      }
      (void)f->reset(b);  // a snapshot's covariance is positive definite (its geometry was checked)
      locked = true;
      health.recovered();
      return;
    }
    if (!locked) return;
    health.record(r.t, f->update(uwb_meas(r, s), Vector<1>(r.range_m)));
    if (health.lockout(r.t)) locked = false;
  }
  void gnss(const messages::GnssFix&) {}
  void epoch(double t) {
    if (now - last_range_t > s.uwb_hold_after_s) locked = false;
    if (locked) held = L::get<"p">(f->belief().mean);
    track.record(t, held, -1, locked);
  }
};
using UwbOnly = UwbOnlyT<>;

}  // namespace ctxfuse::pipelines::region_imm

// The measurement models, recoveries and integrity monitor that every IMU-driven filter of the
// region pipeline shares: one definition of each, so that the methods differ only in how they
// combine them.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <optional>
#include <span>
#include <vector>

#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/filters/multilateration.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/models/planar.hpp"
#include "ctxfuse/pipelines/region_imm/settings.hpp"
#include "ctxfuse/policies/health.hpp"
#include "ctxfuse/policies/integrity.hpp"

namespace ctxfuse::pipelines::region_imm {

inline models::PlanarImuModel process_model(const Settings& s, double factor) {
  models::PlanarImuModel m;
  m.accel_noise_density = s.accel_noise_density * std::sqrt(factor);
  m.gyro_noise_density = s.gyro_noise_density * std::sqrt(factor);
  m.gyro_bias_walk = s.gyro_bias_walk;
  m.accel_bias_walk = s.accel_bias_walk;
  return m;
}

/// R from the receiver's reported horizontal sigma, floored (receivers under-report in multipath).
inline models::PlanarPosition gnss_meas(const messages::GnssFix& e, const Settings& s, double factor = 1.0) {
  models::PlanarPosition m;
  const double sd = std::max(e.std_horizontal(), s.gnss_sigma_floor);
  m.R = SquareMatrix<2>::Identity() * (sd * sd * factor);
  return m;
}
inline models::PlanarRange uwb_meas(const messages::UwbRange& r, const Settings& s, double factor = 1.0) {
  models::PlanarRange m;
  m.anchor = r.anchor_position;
  m.tag_height = s.uwb_tag_height;
  m.sigma = s.uwb_sigma * std::sqrt(factor);
  return m;
}
inline models::PlanarLateralVelocity nhc_meas(const Settings& s, double factor = 1.0) {
  models::PlanarLateralVelocity m;
  m.sigma = s.lateral_sigma * std::sqrt(factor);
  return m;
}
inline models::PlanarBodyVelocity speed_meas(const Settings& s, double factor = 1.0) {
  models::PlanarBodyVelocity m;
  m.forward_sigma = s.speed_sigma * std::sqrt(factor);
  m.lateral_sigma = s.lateral_sigma * std::sqrt(factor);
  return m;
}

/// The GNSS and UWB health of one filter, and the recovery from a lock-out of either.
struct FilterHealth {
  policies::SourceHealth gnss, uwb;
  bool gnss_locked_out = false;  // at the last lockout() that returned true
  FilterHealth() = default;
  explicit FilterHealth(const Settings& s) : gnss(s.health), uwb(s.health) {}
  /// True (and the counts restarted) when either source is locked out at time t.
  bool lockout(double t) {
    gnss_locked_out = gnss.lockout(t);
    if (!gnss_locked_out && !uwb.lockout(t)) return false;
    recovered();
    return true;
  }
  /// Restarts both sources' counts (after a recovery, this filter's own or a wider one).
  void recovered() {
    gnss.recovered();
    uwb.recovered();
  }
  /// The position standard deviation a recovery at an epoch with `fix` (null: none) needs to reach it from
  /// `p`: a filter that ran away from the fixes has to be able to take them again. Leaving a
  /// garage, NLOS ranges whose bias grew smoothly with the distance from the door passed the
  /// gates as motion and left a velocity error; a fixed 2 m widening then took 20 s of
  /// repeated lock-outs to reach fixes 20-40 m away (scenario "paper", seed 1).
  double reach(const messages::GnssFix* fix, const Eigen::Vector2d& p) const {
    return gnss_locked_out && fix ? (Eigen::Vector2d(fix->position.head<2>()) - p).norm() : 0.0;
  }
};

/// Recovery after a lock-out: position and velocity uncertainty added, the position's at least
/// `reach` (FilterHealth::reach).
inline void widen(SquareMatrix<L::size>& P, const Settings& s, double reach = 0.0) {
  policies::widen_block<L, "p">(P, std::max(s.recovery_position_sigma, reach));
  policies::widen_block<L, "v">(P, s.recovery_velocity_sigma);
}

/// Snapshot multilateration of one time stamp's ranges, with the residual test at 3 sigma.
inline MultilaterationOptions snapshot_options(const Settings& s) {
  return {.tag_height_m = s.uwb_tag_height, .sigma_m = s.uwb_sigma, .max_rms_m = 3.0 * s.uwb_sigma};
}

/// Adds `r` to the ranges of one time stamp, starting a new stamp when `r` has another time.
inline void add_to_stamp(std::vector<messages::UwbRange>& stamp, const messages::UwbRange& r) {
  if (!stamp.empty() && std::abs(stamp.front().t - r.t) > 1e-9) stamp.clear();
  stamp.push_back(r);
}

/// The UWB integrity monitor of one IMU-driven filter (Settings::uwb_integrity): gathers the
/// ranges of one time stamp and, once the stamp is complete (the replay has moved on to the
/// next IMU step), checks their snapshot multilateration against the filter's position.
struct UwbIntegrity {
  using Fault = policies::SnapshotIntegrity<2>::Fault;
  const Settings& s;
  policies::SnapshotIntegrity<2> monitor{s.integrity};
  std::vector<messages::UwbRange> ranges{};  // of one time stamp, one per anchor
  int faults = 0;
  bool pending() const { return !ranges.empty(); }
  void add(const messages::UwbRange& r) {
    if (s.uwb_integrity) add_to_stamp(ranges, r);
  }
  /// The fault, if the stamp gathered so far completes a run of disagreements with `b`. (A
  /// template so that only a source that calls it compiles the snapshot solver and monitor.)
  template <class = void>
  std::optional<Fault> flush(const Gaussian<L::size>& b) {
    if (ranges.empty()) return std::nullopt;
    std::optional<Fault> fault;
    if (static_cast<int>(ranges.size()) >= s.integrity_min_anchors) {
      if (const auto snap = multilaterate(ranges, snapshot_options(s)); snap.ok())
        fault = monitor.check(ranges.front().t, snap.position, snap.cov, L::get<"p">(b.mean), L::cov<"p">(b.cov));
    }
    ranges.clear();
    if (fault) ++faults;
    return fault;
  }
};

/// Re-anchors a belief after an integrity fault: the position is the snapshot's, the velocity
/// the run's mean velocity, the heading that velocity's direction when the vehicle moved
/// faster than `reanchor_min_speed` (kept otherwise); their cross-covariances with everything
/// else are dropped, the sensor biases and their covariance kept. The filter's own velocity
/// and heading are not worth keeping: on a mirror track they are the true ones reflected.
inline void reanchor(Gaussian<L::size>& b, const UwbIntegrity::Fault& f, const Settings& s) {
  constexpr int kinematic = L::size_of<"p">() + L::size_of<"v">() + L::size_of<"psi">();
  static_assert(L::offset<"p">() == 0 && L::offset<"v">() == 2 && L::offset<"psi">() == 4,
                "reanchor assumes p, v, psi lead the layout");
  b.cov.topRows<kinematic>().setZero();
  b.cov.leftCols<kinematic>().setZero();
  L::get<"p">(b.mean) = f.position;
  L::cov<"p">(b.cov) = f.cov + Eigen::Matrix2d::Identity() * (s.reanchor_position_sigma * s.reanchor_position_sigma);
  const double var_v = s.reanchor_velocity_sigma * s.reanchor_velocity_sigma;
  if (f.velocity) {
    L::get<"v">(b.mean) = *f.velocity;
    if (f.velocity->norm() > s.reanchor_min_speed) L::get<"psi">(b.mean)(0) = std::atan2(f.velocity->y(), f.velocity->x());
  }
  L::cov<"v">(b.cov) = Eigen::Matrix2d::Identity() * var_v;
  L::cov<"psi">(b.cov)(0, 0) = s.reanchor_heading_sigma * s.reanchor_heading_sigma;
}

}  // namespace ctxfuse::pipelines::region_imm

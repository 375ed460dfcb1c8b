// The belief the GNSS/INS forward pass (forward.hpp) starts from once the dynamic alignment
// (models/alignment.hpp) has one: position, velocity and heading from the fixes; roll, pitch
// and gyro bias from the static start (level as mounted, with a wide sigma, when the
// recording starts moving), or, after an IMU gap (ForwardPass::lose), everything the gap does
// not change from the belief the pass lost. A pure function of its inputs.
#pragma once

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

#include "ctxfuse/models/earth.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/models/alignment.hpp"
#include "ctxfuse/models/ins_augment.hpp"
#include "ctxfuse/models/ins_motion.hpp"
#include "ctxfuse/pipelines/gins/settings.hpp"
#include "ctxfuse/pipelines/gins/static_start.hpp"

namespace ctxfuse::pipelines::gins {

using Nav15 = models::InsNavModel<models::FullStrapdown>;
/// The 20-state layout: mounting pitch/heading of the vehicle in the body frame and the lever
/// arm from the IMU to the vehicle point where the non-holonomic constraint holds.
using Nav20 = models::Augmented<Nav15, StateBlock<"mount", 2>, StateBlock<"lever", 3>>;

template <class Model>
models::NavState nav_part(const typename Model::State& x) {
  if constexpr (requires { Model::base_part(x); }) return Model::base_part(x); else return x;
}

/// The GNSS/INS alignment (models/alignment.hpp): the receiver's velocity or a straight
/// baseline, floored by the start's sigmas.
inline models::AlignmentOptions alignment_options(const Settings& s) {
  models::AlignmentOptions o;
  o.max_span_s = s.alignment_max_span_s;
  o.min_distance_m = s.alignment_min_distance_m;
  o.max_heading_sigma = s.alignment_max_heading_sigma;
  o.velocity_baseline_s = 1.0;
  o.straight_track = true;
  o.velocity_sigma_floor_mps = s.initial_velocity_sigma;
  o.heading_sigma_floor = s.initial_heading_sigma;
  return o;
}

/// a: the alignment in the (north, east) plane (position, horizontal velocity, heading = NED
/// yaw, with their covariances); fix, z [rad, rad, m], cov [m^2, NED]: the fix that completed
/// it; gnss_lever: IMU to antenna, nhc_lever: IMU to the NHC point (body axes); start: the
/// static start (none: roll and pitch zero with initial_roll_pitch_sigma_unlevelled); lost:
/// the belief before an IMU gap, or nullptr at the start.
template <class Model>
eskf::Belief<Model> initial_belief(const Settings& s, const models::PlanarAlignment& a, const messages::GnssFix& fix,
                                   const Eigen::Vector3d& z, const Eigen::Matrix3d& cov, const Eigen::Vector3d& gnss_lever,
                                   const Eigen::Vector3d& nhc_lever, const StaticStats& start, const eskf::Belief<Model>* lost) {
  using S = typename Model::State;
  // Roll and pitch from the static start's mean specific force (f = -C' g at rest); after a
  // loss, the filter's own; with neither, level as mounted.
  double roll = 0.0, pitch = 0.0;
  double rp_sigma = s.initial_roll_pitch_sigma;
  if (lost) {
    const Eigen::Matrix3d C = nav_part<Model>(lost->nominal).template get<"theta">().toRotationMatrix();
    roll = std::atan2(C(2, 1), C(2, 2));
    pitch = -std::asin(std::clamp(C(2, 0), -1.0, 1.0));
  } else if (start.samples > 0) {
    const Eigen::Vector3d& f = start.accel_mean;
    roll = std::atan2(-f(1), -f(2));
    pitch = std::atan2(f(0), std::hypot(f(1), f(2)));
  } else {
    rp_sigma = s.initial_roll_pitch_sigma_unlevelled;
  }
  // Heading: the alignment's (the receiver's velocity direction or a straight baseline).
  const double yaw = a.heading;
  const Eigen::Quaterniond q = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
  models::NavState nav;
  nav.get<"theta">() = q;
  if (lost) {
    nav.get<"bg">() = nav_part<Model>(lost->nominal).template get<"bg">();
    nav.get<"ba">() = nav_part<Model>(lost->nominal).template get<"ba">();
  } else if (start.samples > 0) {
    // The static mean holds the earth's rate too, which the full mechanisation models.
    nav.get<"bg">() = start.gyro_mean - q.conjugate() * earth::earth_rate_ned(z(0));
  }
  // Velocity: the receiver's when it reports one (an instant's, not a baseline's mean).
  nav.get<"v">() = Eigen::Vector3d(a.velocity.x(), a.velocity.y(), 0.0);
  Eigen::Vector2d v_var = a.velocity_cov.diagonal();
  if (fix.velocity) {
    nav.get<"v">() = Eigen::Vector3d(fix.velocity->y(), fix.velocity->x(), -fix.velocity->z());
    v_var = Eigen::Vector2d(fix.velocity_cov(1, 1), fix.velocity_cov(0, 0));
  }
  nav.get<"p">() = earth::GeodeticRetraction::inject(z, -(q * gnss_lever));
  eskf::Belief<Model> b;
  if constexpr (requires { Model::set_base_part(b.nominal, nav); }) {
    if (lost) b.nominal = lost->nominal;  // the extra blocks as they were
    Model::set_base_part(b.nominal, nav);
    if (!lost) b.nominal.template get<"lever">() = nhc_lever;
  } else {
    b.nominal = nav;
  }
  using L = typename Model::ErrorLayout;
  b.cov.setZero();
  L::template cov<"p">(b.cov) = cov;
  const double v2 = s.initial_velocity_sigma * s.initial_velocity_sigma;
  L::template cov<"v">(b.cov).diagonal() << std::max(v_var(0), v2), std::max(v_var(1), v2), v2;
  const double rp = rp_sigma * rp_sigma;
  L::template cov<"theta">(b.cov).diagonal() << rp, rp, std::max(a.heading_var, s.initial_heading_sigma * s.initial_heading_sigma);
  L::template cov<"bg">(b.cov).diagonal().setConstant(s.initial_gyro_bias_sigma * s.initial_gyro_bias_sigma);
  L::template cov<"ba">(b.cov).diagonal().setConstant(s.initial_accel_bias_sigma * s.initial_accel_bias_sigma);
  if constexpr (S::has("mount")) {
    L::template cov<"mount">(b.cov).diagonal().setConstant(s.initial_mount_sigma * s.initial_mount_sigma);
    L::template cov<"lever">(b.cov).diagonal().setConstant(s.initial_lever_sigma * s.initial_lever_sigma);
  }
  if (lost) {  // what the gap did not change keeps its own (marginal) covariance
    L::template cov<"bg">(b.cov) = L::template cov<"bg">(lost->cov);
    L::template cov<"ba">(b.cov) = L::template cov<"ba">(lost->cov);
    if constexpr (S::has("mount")) {
      L::template cov<"mount">(b.cov) = L::template cov<"mount">(lost->cov);
      L::template cov<"lever">(b.cov) = L::template cov<"lever">(lost->cov);
    }
  }
  return b;
}

}  // namespace ctxfuse::pipelines::gins

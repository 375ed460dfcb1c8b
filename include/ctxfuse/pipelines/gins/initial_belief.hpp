// The belief the GNSS/INS forward pass (forward.hpp) starts from once the dynamic alignment has
// a state: position, velocity and heading from the fixes; roll, pitch and gyro bias from the
// static start, or, after an IMU gap (ForwardPass::lose), everything the gap does not change
// from the belief the pass lost. A pure function of its inputs.
#pragma once

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

#include "ctxfuse/models/earth.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/io/messages.hpp"
#include "ctxfuse/models/ins_augment.hpp"
#include "ctxfuse/models/ins_motion.hpp"
#include "ctxfuse/pipelines/gins/settings.hpp"
#include "ctxfuse/pipelines/gins/static_start.hpp"

namespace ctxfuse::pipelines::gins {

using Nav15 = models::InsNavModel<models::FullStrapdown>;
/// The 20-state layout: mounting pitch/heading of the vehicle in the body frame and the lever
/// arm from the IMU to the vehicle point where the non-holonomic constraint holds.
using Nav20 = models::Augmented<Nav15, Block<"mount", 2>, Block<"lever", 3>>;

template <class Model>
models::NavState nav_part(const typename Model::State& x) {
  if constexpr (requires { Model::base_part(x); }) return Model::base_part(x); else return x;
}

/// nav: the aligner's state (position, velocity and heading from two fixes); fix, z [rad, rad,
/// m], cov [m^2, NED]: the fix that completed it; gnss_lever: IMU to antenna, nhc_lever: IMU to
/// the NHC point (body axes); lost: the belief before an IMU gap, or nullptr at the start.
template <class Model>
eskf::Belief<Model> initial_belief(const Settings& s, models::NavState nav, const io::GnssFix& fix, const Eigen::Vector3d& z,
                                   const Eigen::Matrix3d& cov, const Eigen::Vector3d& gnss_lever,
                                   const Eigen::Vector3d& nhc_lever, const StaticStats& start,
                                   const eskf::Belief<Model>* lost) {
  using S = typename Model::State;
  // Roll and pitch from the static start's mean specific force (f = -C' g at rest); after a
  // loss, the filter's own.
  double roll = 0.0, pitch = 0.0;
  if (lost) {
    const Eigen::Matrix3d C = nav_part<Model>(lost->nominal).template get<"theta">().toRotationMatrix();
    roll = std::atan2(C(2, 1), C(2, 2));
    pitch = -std::asin(std::clamp(C(2, 0), -1.0, 1.0));
  } else if (start.samples > 0) {
    const Eigen::Vector3d& f = start.accel_mean;
    roll = std::atan2(-f(1), -f(2));
    pitch = std::atan2(f(0), std::hypot(f(1), f(2)));
  }
  // Heading: the fix's own velocity direction when it has one (the instant's track; the
  // displacement over the last second lags a turn by half a second), else the displacement.
  double yaw = models::heading_of(nav.get<"theta">().toRotationMatrix());
  if (fix.velocity && fix.velocity->head<2>().norm() > 0.5 * s.alignment_min_distance_m / s.alignment_interval_s)
    yaw = std::atan2(fix.velocity->x(), fix.velocity->y());
  const Eigen::Quaterniond q = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
  nav.get<"theta">() = q;
  if (lost) {
    nav.get<"bg">() = nav_part<Model>(lost->nominal).template get<"bg">();
    nav.get<"ba">() = nav_part<Model>(lost->nominal).template get<"ba">();
  } else if (start.samples > 0) {
    // The static mean holds the earth's rate too, which the full mechanisation models.
    nav.get<"bg">() = start.gyro_mean - q.conjugate() * earth::earth_rate_ned(z(0));
  }
  if (fix.velocity) nav.get<"v">() = Eigen::Vector3d(fix.velocity->y(), fix.velocity->x(), -fix.velocity->z());
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
  L::template cov<"v">(b.cov).diagonal().setConstant(s.initial_velocity_sigma * s.initial_velocity_sigma);
  const double rp = s.initial_roll_pitch_sigma * s.initial_roll_pitch_sigma;
  L::template cov<"theta">(b.cov).diagonal() << rp, rp, s.initial_heading_sigma * s.initial_heading_sigma;
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

// How the region pipeline's filters start without truth: dynamic alignment from position
// fixes. A planar IMU filter needs position, velocity and heading; a vehicle that moves
// forward (no side slip) gives the heading as the direction between two fixes, once they are
// far enough apart that the fixes' noise cannot turn it much. The fixes are GNSS fixes or, where
// no GNSS reaches (a drive that starts in a garage), UWB snapshot multilaterations.
//
// The initial covariance comes from the fixes themselves (position: the last fix; velocity:
// the difference of two fixes over their time apart; heading: the difference's cross-track
// spread over its length), each floored by Settings::init_*_sigma, since the vehicle may have
// turned or changed speed between the two fixes. What the fixes cannot see (sensor biases)
// starts at zero with Settings::init_*_bias_sigma.
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <numbers>
#include <optional>

#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/models/alignment.hpp"
#include "ctxfuse/pipelines/region_imm/settings.hpp"

namespace ctxfuse::pipelines::region_imm {

/// Position, velocity and heading at time t (models/alignment.hpp).
using Alignment = models::PlanarAlignment;

/// Motion known from elsewhere at the first fix (a static alignment with a magnetometer, the
/// end of a previous drive): the filters then start at the first fix with it.
struct KnownMotion {
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();
  double heading = 0.0;
};

/// The region pipeline's alignment (models::DynamicAligner): baselines between fixes (no
/// receiver velocity), floored by the initial sigmas.
inline models::AlignmentOptions alignment_options(const Settings& s) {
  models::AlignmentOptions o;
  o.max_span_s = s.align_max_span_s;
  o.min_distance_m = s.align_min_distance_m;
  o.max_heading_sigma = s.align_max_heading_sigma_deg * std::numbers::pi / 180.0;
  o.velocity_baseline_s = s.align_velocity_baseline_s;
  o.position_sigma_floor_m = s.init_position_sigma;
  o.velocity_sigma_floor_mps = s.init_velocity_sigma;
  o.heading_sigma_floor = s.init_heading_sigma_deg * std::numbers::pi / 180.0;
  return o;
}

/// The planar filters' initial belief from an alignment.
inline Gaussian<L::size> initial_belief(const Alignment& a, const Settings& s) {
  Gaussian<L::size> b;
  b.mean.setZero();
  L::get<"p">(b.mean) = a.position;
  L::get<"v">(b.mean) = a.velocity;
  L::get<"psi">(b.mean)(0) = a.heading;
  b.cov.setZero();
  L::cov<"p">(b.cov) = a.position_cov;
  L::cov<"v">(b.cov) = a.velocity_cov;
  L::cov<"psi">(b.cov)(0, 0) = a.heading_var;
  L::cov<"bg">(b.cov)(0, 0) = s.init_gyro_bias_sigma * s.init_gyro_bias_sigma;
  L::cov<"ba">(b.cov).diagonal().setConstant(s.init_accel_bias_sigma * s.init_accel_bias_sigma);
  return b;
}

/// The initial belief at a first fix `p0` with known motion: position, velocity and heading
/// with the fixed initial sigmas of Settings.
inline Gaussian<L::size> initial_belief(const Eigen::Vector2d& p0, const KnownMotion& m, const Settings& s) {
  Gaussian<L::size> b;
  b.mean.setZero();
  L::get<"p">(b.mean) = p0;
  L::get<"v">(b.mean) = m.velocity;
  L::get<"psi">(b.mean)(0) = m.heading;
  Vector<L::size> sd;
  const double h = s.init_heading_sigma_deg * std::numbers::pi / 180.0;
  sd << s.init_position_sigma, s.init_position_sigma, s.init_velocity_sigma, s.init_velocity_sigma, h,
      s.init_gyro_bias_sigma, s.init_accel_bias_sigma, s.init_accel_bias_sigma;
  b.cov = sd.cwiseProduct(sd).asDiagonal();
  return b;
}

}  // namespace ctxfuse::pipelines::region_imm

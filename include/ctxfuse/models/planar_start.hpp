// How a planar IMU filter (models/planar.hpp) runs on sensor messages and starts without truth:
// an IMU sample as the model's input, and the start from a dynamic alignment of position fixes
// (models/alignment.hpp) or from motion known elsewhere. One definition for every pipeline with
// a planar IMU filter (the region pipeline's filters, the NLOS UWB pipeline's IMU filters).
//
// A planar IMU filter needs position, velocity and heading; a vehicle that moves forward (no
// side slip) gives the heading as the direction between two fixes once they are far enough
// apart that the fixes' noise cannot turn it much. The initial covariance comes from the fixes
// themselves, each floored by the init_* sigmas, since the vehicle may have turned or changed
// speed between the two fixes. What the fixes cannot see (sensor biases) starts at zero with the
// init_*_bias sigmas.
#pragma once

#include <Eigen/Core>

#include <numbers>

#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/models/alignment.hpp"
#include "ctxfuse/models/planar.hpp"

namespace ctxfuse::models {

/// The planar model's input from an IMU sample (rates, vehicle axes: yaw rate about z, specific
/// force along x and y).
inline PlanarImu planar_input(const messages::ImuSample& s) {
  PlanarImu u;
  u.yaw_rate = s.gyro.z();
  u.accel = s.accel.head<2>();
  return u;
}

/// The start's settings, in the units settings are written in (degrees).
struct PlanarStartSettings {
  // Dynamic alignment from position fixes (GNSS fixes, or UWB snapshots where no GNSS reaches):
  // the heading is the direction between two fixes more than `align_min_distance_m` apart
  // within `align_max_span_s`, taken once the fixes' own reported noise puts its 1-sigma below
  // `align_max_heading_sigma_deg` (with a 1.5 m receiver sigma, about 25 m of straight travel);
  // the velocity is the displacement over the last `align_velocity_baseline_s` or more.
  // Uncertainties follow from the fixes' covariances.
  double align_min_distance_m = 5.0;
  double align_max_span_s = 10.0;
  double align_max_heading_sigma_deg = 5.0;
  double align_velocity_baseline_s = 1.0;
  // Initial uncertainty of what the alignment does not observe, and the floors of what it does
  // (the vehicle may have turned or changed speed between the fixes).
  double init_position_sigma = 3.0, init_velocity_sigma = 0.2, init_heading_sigma_deg = 2.0;
  double init_gyro_bias_sigma = 1e-3, init_accel_bias_sigma = 0.05;

  /// The aligner's options (models::DynamicAligner): baselines between fixes (no receiver
  /// velocity), floored by the initial sigmas.
  AlignmentOptions alignment_options() const {
    AlignmentOptions o;
    o.max_span_s = align_max_span_s;
    o.min_distance_m = align_min_distance_m;
    o.max_heading_sigma = align_max_heading_sigma_deg * std::numbers::pi / 180.0;
    o.velocity_baseline_s = align_velocity_baseline_s;
    o.position_sigma_floor_m = init_position_sigma;
    o.velocity_sigma_floor_mps = init_velocity_sigma;
    o.heading_sigma_floor = init_heading_sigma_deg * std::numbers::pi / 180.0;
    return o;
  }
};

/// Motion known from elsewhere at the first fix (a static alignment with a magnetometer, the
/// end of a previous drive): the filters then start at the first fix with it.
struct KnownMotion {
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();
  double heading = 0.0;
};

/// The planar filters' initial belief from an alignment.
inline Gaussian<PlanarLayout::size> planar_initial_belief(const PlanarAlignment& a, const PlanarStartSettings& s) {
  using L = PlanarLayout;
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
/// with the fixed initial sigmas.
inline Gaussian<PlanarLayout::size> planar_initial_belief(const Eigen::Vector2d& p0, const KnownMotion& m,
                                                          const PlanarStartSettings& s) {
  using L = PlanarLayout;
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

}  // namespace ctxfuse::models

// Settings of the GNSS/INS error-state pipeline (pipelines/gins): the installation of one
// recording (given per recording, e.g. from `ctxfuse run gins --imu-rpy ...`), and ONE set of
// noise and constraint figures for every recording, each saying where it comes from. Nothing
// here is fitted to an outage error.
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <numbers>

#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/policies/health.hpp"

namespace ctxfuse::pipelines::gins {

inline constexpr double kDeg = std::numbers::pi / 180.0;
inline constexpr double kStandardGravity = 9.80665;

/// Where the sensors sit. Lever arms from the system origin in body axes (forward, right,
/// down) [m]; the body frame is the vehicle's. The non-holonomic constraint holds at the origin.
struct Installation {
  Eigen::Vector3d imu_rpy_deg = Eigen::Vector3d::Zero();  // IMU axes -> body (roll, pitch, yaw)
  Eigen::Vector3d imu_lever_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d gnss_lever_m = Eigen::Vector3d::Zero();
  double imu_delay_s = 0.0;  // added to every IMU stamp
};

/// Which vehicle constraints the filter applies.
struct Constraints {
  bool zupt = false;  // zero velocity while the raw IMU says static
  bool zihr = false;  // heading held from the start of each static period
  bool nhc = false;   // no lateral / vertical velocity of the origin while moving
  bool mag = false;   // magnetometer heading relative to a quasi-static epoch (needs a mag stream)
  bool any() const { return zupt || zihr || nhc || mag; }
};

struct Settings {
  // --- IMU white noise ------------------------------------------------------------------
  // The data sheet gives 0.0038 deg/s/sqrt(Hz) and 70 ug/sqrt(Hz) (data README, upstream
  // figures). In the car the idling engine shakes the IMU far more: over the drive's static
  // start (3061 static samples before the alignment, `ctxfuse run gins --data DIR --json`,
  // "static_start") the 100 Hz samples scatter by 0.393 / 2.324 / 0.128 deg/s (gyro) and
  // 0.088 / 0.086 / 0.130 m/s^2 per body axis. That scatter is mostly vibration at tens of Hz,
  // which the strapdown integration averages out; what it integrates into attitude and
  // velocity error is the noise at the filter's time scales, the Allan deviation at 1 s of the
  // same samples (IEEE Std 952, annex C: white noise of density N gives N at 1 s;
  // "gyro_allan_1s_dps", "accel_allan_1s_mps2"): 0.028 / 0.099 / 0.026 deg/s and 0.0147 /
  // 0.0101 / 0.0115 m/s^2, from 33 cluster differences (about 12 % statistical uncertainty).
  // The scatter read as white noise (std / sqrt(100 Hz)) would claim 0.233 deg/s/sqrt(Hz),
  // 2.4x more. The strapdown noise is isotropic: each density is the largest axis' figure.
  double gyro_noise_density = 0.099 * kDeg;  // [rad/s/sqrt(Hz)]
  double accel_noise_density = 0.0147;       // [m/s^2/sqrt(Hz)]
  // --- IMU gaps ---------------------------------------------------------------------------
  // A sample stands for the motion until the next one; held longer than imu_hold_s (the next
  // did not come), or refused and replaced by the last one, the time is unmeasured. A car's
  // yaw rate changes by several deg/s within a second (a 90 deg turn at a junction takes
  // 5-10 s, 9-18 deg/s reached within a second or two), so a sample held for 1 s is off by
  // about 2 deg in heading (1/2 x 4 deg/s^2 x 1 s^2), the heading sigma of an alignment: past
  // imu_max_unmeasured_s in a row the pass stops and re-aligns from the fixes
  // (ForwardPass::lose). 50 ms is five sample intervals at 100 Hz, one at 20 Hz.
  double imu_hold_s = 0.05;
  double imu_max_unmeasured_s = 1.0;
  // --- Bias instability (data sheet, as random walks) -------------------------------------
  double gyro_bias_density = 3.8e-5 * kDeg;                // [rad/s^2/sqrt(Hz)]
  double accel_bias_density = 7e-6 * kStandardGravity;     // [m/s^3/sqrt(Hz)]

  // --- Start ------------------------------------------------------------------------------
  // Gyro bias: the mean rate over the static start (earth rate, 0.004 deg/s at most, left
  // in); its 1-sigma is the data sheet's bias instability integrated over the drive's length
  // plus the mean's own scatter, bounded below by this figure.
  double initial_gyro_bias_sigma = 0.02 * kDeg;  // [rad/s]
  // Accelerometer bias: the turn-on bias of a consumer MEMS part (a few mg); levelling on it
  // absorbs the horizontal part into roll and pitch, hence the attitude sigma below.
  double initial_accel_bias_sigma = 0.03;        // [m/s^2] (3 mg)
  double initial_roll_pitch_sigma = 0.5 * kDeg;  // levelling from the static start
  // A recording that starts moving has no static start to level on: roll and pitch start at
  // zero in the body frame (the platform level as mounted) with this sigma, a ground
  // platform's slope and a held device's tilt (10 deg, about a 18 % grade).
  double initial_roll_pitch_sigma_unlevelled = 10.0 * kDeg;
  // Heading: the alignment's own sigma (models/alignment.hpp), floored by how far the body's
  // forward axis may point from the direction of travel (Platform below: 2 deg for a car that
  // may crab or a robot, 15 deg for a device held in the hand).
  double initial_heading_sigma = 2.0 * kDeg;
  double initial_velocity_sigma = 0.2;           // [m/s] the fix's velocity
  // 20-state blocks: the vehicle's mounting pitch/heading in the body frame after the given
  // installation angles (a residual of a hand-measured installation, ~1 deg) and the lever arm
  // to the NHC point (the given lever arms, hand-measured to ~10 cm).
  double initial_mount_sigma = 1.0 * kDeg;
  double initial_lever_sigma = 0.1;  // [m]
  // Dynamic alignment (models/alignment.hpp): heading from the receiver's velocity or the
  // longest straight baseline of the last 10 s, once its 1-sigma from the fixes' own
  // covariances is below alignment_max_heading_sigma. With RTK fixes (5 cm floor below) 2 deg
  // needs a 2 m baseline: a car within a second of moving off, a 0.3 m/s robot within 7 s.
  // Baselines shorter than 1 m are not used (a standing platform's fixes scatter by
  // centimetres to decimetres).
  double alignment_max_span_s = 10.0;
  double alignment_min_distance_m = 1.0;
  double alignment_max_heading_sigma = 2.0 * kDeg;

  // --- GNSS -------------------------------------------------------------------------------
  // R from the receiver's own sd columns, floored by the solution's quality: receivers report
  // float and single solutions with sigmas as small as a fixed one's. RTK fixed: the antenna's
  // phase centre, multipath and the lever arm's own error are a few cm (RTKLIB claims 1 cm);
  // PPP 10 cm; RTK float decimetres (25 cm); DGNSS 0.5 m; SBAS 1 m; a single-point solution
  // 1.5 m (a code receiver's horizontal accuracy in open sky); unknown as single.
  double gnss_position_sigma_floor_m = 0.05;  // RTK fixed
  double gnss_ppp_sigma_floor_m = 0.10;
  double gnss_float_sigma_floor_m = 0.25;
  double gnss_dgnss_sigma_floor_m = 0.5;
  double gnss_sbas_sigma_floor_m = 1.0;
  double gnss_single_sigma_floor_m = 1.5;
  double gnss_sigma_floor(messages::FixQuality q) const {
    switch (q) {
      case messages::FixQuality::fixed: return gnss_position_sigma_floor_m;
      case messages::FixQuality::ppp: return gnss_ppp_sigma_floor_m;
      case messages::FixQuality::floating: return gnss_float_sigma_floor_m;
      case messages::FixQuality::dgps: return gnss_dgnss_sigma_floor_m;
      case messages::FixQuality::sbas: return gnss_sbas_sigma_floor_m;
      default: return gnss_single_sigma_floor_m;
    }
  }
  double gnss_velocity_sigma_floor_mps = 0.05;
  bool use_gnss_velocity = true;
  // Textbook one-tailed test at 99.9 %: a fix outside it is refused, not forced in.
  double gate_probability = 0.999;
  // Three fixes in a row outside the gate (3 s at 1 Hz) cannot all be receiver faults at
  // 1 - 0.999 each: the next one is released into the filter (policies/health.hpp's lock-out,
  // here with no timeout; filters/release.hpp). The fixes' positions and velocities count
  // their refusals separately.
  policies::SourceHealthOptions gate_release{0.0, 3};

  // --- Constraints ------------------------------------------------------------------------
  // Applied every constraint_interval_s (10 Hz: the car's suspension and steering change the
  // violation at a few Hz; faster updates would treat correlated violations as white).
  double constraint_interval_s = 0.1;
  // Static detection (static_start.hpp): the window in seconds, upstream's ZUPT window (data
  // README: 50 epochs of its 100 Hz IMU). The thresholds on the window's mean rate and std of
  // |f| come from the recording's own static start, once it has lasted
  // static_calibration_min_s (static_thresholds_from_rest: a window at rest fails each test
  // with probability static_false_alarm, floored by the data sheet's white noise, 0.0038
  // deg/s/sqrt(Hz) and 70 ug/sqrt(Hz)). Until then, and for a whole recording that starts
  // moving or whose start is shorter, upstream's thresholds (0.25 deg/s, 0.25 m/s^2) are the
  // fallback; they find the static start in the first place. The mean horizontal acceleration
  // test keeps static_accel_threshold: it separates steady braking (1-2 m/s^2) from rest, a
  // property of the motion, not of the IMU's noise (0.25 m/s^2 is also a 1.5 deg tilt error).
  double static_window_s = 0.5;
  double static_accel_threshold = 0.25;
  double static_gyro_threshold = 0.25 * kDeg;
  bool static_thresholds_from_start = true;
  double static_calibration_min_s = 5.0;
  double static_false_alarm = 1e-3;
  double static_gyro_floor_density = 0.0038 * kDeg;               // [rad/s/sqrt(Hz)]
  double static_accel_floor_density = 70e-6 * kStandardGravity;   // [m/s^2/sqrt(Hz)]
  // Steady straight motion reads as still to an IMU (a smooth robot at 0.3 m/s): a still IMU
  // is static only while the filter's horizontal speed, and the latest used GNSS velocity if
  // it is under static_gnss_hold_s old, are below static_max_speed_mps (forward.hpp). A ZUPT
  // taken while moving stops the platform in the filter; one missed at rest costs little. The
  // decision is on the speeds themselves, not on their sigmas: in an outage the filter's
  // along-track velocity sigma grows past the platform's speed (a 3 mg bias prior: 0.3 m/s
  // in 10 s), while its best estimate still says it moves. 0.1 m/s: twice the GNSS velocity's
  // floor, a third of the slowest platform's speed (a robot at 0.3 m/s). The GNSS velocity
  // holds for a 1 Hz receiver's interval and half of it.
  double static_max_speed_mps = 0.1;
  double static_gnss_hold_s = 1.5;
  double zupt_sigma_mps = 0.02;      // a parked car's rocking on its suspension
  double zihr_sigma = 0.1 * kDeg;    // heading of a parked car
  // NHC: side slip and suspension travel of a car on a road, 0.1 m/s (a slip angle of 0.5 deg
  // at 10 m/s, typical of normal driving).
  double nhc_sigma_mps = 0.1;
  double mag_heading_sigma = 2.0 * kDeg;
};

/// The kind of platform the sensors ride on: what the constraints may assume.
enum class Platform { car, pedestrian, robot };

inline const char* name_of(Platform p) {
  return p == Platform::car ? "car" : p == Platform::pedestrian ? "pedestrian" : "robot";
}

/// The constraints a platform allows: a wheeled platform neither slips sideways nor leaves the
/// ground (NHC) and stands still when parked (ZUPT); a walker's device stands still only while
/// its holder does (ZUPT) and moves sideways at will (no NHC).
inline Constraints default_constraints(Platform p) {
  Constraints c;
  c.zupt = true;
  c.nhc = p != Platform::pedestrian;
  return c;
}

/// The settings for a platform: the same noise figures, and what differs with the platform.
///  - car: as Settings (a parked car's rocking 0.02 m/s; side slip 0.1 m/s; forward axis within
///    2 deg of the track).
///  - pedestrian: a device held in the hand while its holder stands sways by centimetres a
///    second (ZUPT 0.05 m/s) and points within 15 deg of the walking direction (heading floor);
///    the alignment waits for 5 deg, a third of that.
///  - robot: a parked robot is rigid (ZUPT 0.01 m/s); a skid-steered or differential-drive
///    base slips sideways in turns by a few cm/s at walking speed (NHC 0.05 m/s); its forward
///    axis is the direction of travel within 2 deg, and at 0.3 m/s it waits for 3 deg (a 1.4 m
///    baseline with RTK fixes) rather than 2.
inline Settings settings_for(Platform p, Settings s = {}) {
  switch (p) {
    case Platform::car: break;
    case Platform::pedestrian:
      s.zupt_sigma_mps = 0.05;
      s.initial_heading_sigma = 15.0 * kDeg;
      s.alignment_max_heading_sigma = 5.0 * kDeg;
      break;
    case Platform::robot:
      s.zupt_sigma_mps = 0.01;
      s.nhc_sigma_mps = 0.05;
      s.alignment_max_heading_sigma = 3.0 * kDeg;
      break;
  }
  return s;
}

}  // namespace ctxfuse::pipelines::gins

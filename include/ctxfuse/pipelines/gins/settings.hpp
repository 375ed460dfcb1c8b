// Settings of the GNSS/INS error-state pipeline (pipelines/gins): the installation of one
// recording (given per recording, e.g. from `ctxfuse run gins --imu-rpy ...`), and ONE set of
// noise and constraint figures for every recording, each saying where it comes from. Nothing
// here is fitted to an outage error.
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <numbers>

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
  double initial_heading_sigma = 2.0 * kDeg;     // from two fixes > 5 m apart (1 cm each) in a car that may crab
  double initial_velocity_sigma = 0.2;           // [m/s] the fix's velocity
  // 20-state blocks: the vehicle's mounting pitch/heading in the body frame after the given
  // installation angles (a residual of a hand-measured installation, ~1 deg) and the lever arm
  // to the NHC point (the given lever arms, hand-measured to ~10 cm).
  double initial_mount_sigma = 1.0 * kDeg;
  double initial_lever_sigma = 0.1;  // [m]
  // Dynamic alignment: two good fixes 1 s apart (issue 17) and far enough apart that their
  // noise (the 5 cm floor below, sqrt(2) x for the difference) leaves the heading within the
  // 2 deg above: 0.07 m / tan(2 deg) = 2 m. (The 5 m is for metre-level fixes; with
  // RTK it would hold the start back until the car reaches 5 m/s.)
  double alignment_interval_s = 1.0;
  double alignment_min_distance_m = 2.0;

  // --- GNSS -------------------------------------------------------------------------------
  // R from the receiver's own sd columns, floored: RTKLIB's fixed solutions claim 1 cm, but
  // the antenna's phase centre, multipath and the lever arm's own error are a few cm.
  double gnss_position_sigma_floor_m = 0.05;
  double gnss_velocity_sigma_floor_mps = 0.05;
  bool use_gnss_velocity = true;
  // Textbook one-tailed test at 99.9 %: a fix outside it is refused, not forced in.
  double gate_probability = 0.999;
  // Three fixes in a row outside the gate (3 s at 1 Hz) cannot all be receiver faults at
  // 1 - 0.999 each: the next one is released into the filter (ForwardPass::release). The
  // fixes' positions and velocities count their refusals separately.
  int gate_release_count = 3;

  // --- Constraints ------------------------------------------------------------------------
  // Applied every constraint_interval_s (10 Hz: the car's suspension and steering change the
  // violation at a few Hz; faster updates would treat correlated violations as white).
  double constraint_interval_s = 0.1;
  // Static detection: upstream's ZUPT window and thresholds (data README): 50 epochs,
  // 0.25 m/s^2, 0.25 deg/s.
  int static_window = 50;
  double static_accel_threshold = 0.25;
  double static_gyro_threshold = 0.25 * kDeg;
  double zupt_sigma_mps = 0.02;      // a parked car's rocking on its suspension
  double zihr_sigma = 0.1 * kDeg;    // heading of a parked car
  // NHC: side slip and suspension travel of a car on a road, 0.1 m/s (a slip angle of 0.5 deg
  // at 10 m/s, typical of normal driving).
  double nhc_sigma_mps = 0.1;
  double mag_heading_sigma = 2.0 * kDeg;
};

}  // namespace ctxfuse::pipelines::gins

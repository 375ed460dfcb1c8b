// Sensor messages: what a recording or the simulator delivers, and nothing more. No message
// carries truth or labels (true ranges, NLOS flags, regions); those are separate records
// that only eval/ and the CLI's scoring read (sim::TruthLog, sim/records.hpp). The bottom
// layer beside core/: every folder may include it. Every message is time-stamped
// in seconds on one clock per log; the replay (io/replay.hpp) merges streams by that stamp.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace ctxfuse::messages {

inline constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();

/// One inertial sample in the IMU's own axes. With `increments` false, `gyro` [rad/s] and
/// `accel` [m/s^2, specific force] are the rates at `t`; with it true they are the angle
/// [rad] and velocity [m/s] increments over the interval that ends at `t`.
/// The one IMU sample type of the library: what readers and the simulator deliver, and the
/// input of the rate-driven INS model (models::Ins15Model, which refuses increments).
struct ImuSample {
  double t = 0.0;
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();
  bool increments = false;
  bool is_finite() const { return std::isfinite(t) && gyro.allFinite() && accel.allFinite(); }
  /// The largest |element| of gyro and accel (the filters' input-magnitude check).
  double max_abs() const { return std::max(gyro.cwiseAbs().maxCoeff(), accel.cwiseAbs().maxCoeff()); }
};

enum class PositionFrame : std::uint8_t {
  local_enu,  // east, north, up [m] from the log's own origin
  geodetic,   // latitude [deg], longitude [deg], height [m]
};

/// Receiver solution quality (RTKLIB's Q codes where they apply).
enum class FixQuality : std::uint8_t { fixed = 1, floating = 2, sbas = 3, dgps = 4, single = 5, ppp = 6, unknown = 0 };

/// One position fix from a GNSS receiver. The covariance is in east/north/up axes [m^2]
/// whatever `frame` the position is in.
struct GnssFix {
  double t = 0.0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  PositionFrame frame = PositionFrame::local_enu;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Identity();
  std::optional<Eigen::Vector3d> velocity;                  // east, north, up [m/s]
  Eigen::Matrix3d velocity_cov = Eigen::Matrix3d::Zero();  // [m^2/s^2], when velocity is set
  FixQuality quality = FixQuality::unknown;
  int satellites_used = 0;
  /// The receiver's reported 1-sigma of one horizontal axis (sqrt of the mean of the east and
  /// north variances).
  double std_horizontal() const;
};

/// One tracked satellite. Elevation and azimuth are NaN when the receiver did not report
/// them (u-blox sends -91 or leaves the field empty); such a satellite counts as tracked.
struct SatObservation {
  int sat_id = 0;
  double elevation_deg = kUnknown;
  double azimuth_deg = kUnknown;  // clockwise from north
  double cn0_dbhz = 0.0;
  bool has_geometry() const { return elevation_deg == elevation_deg && azimuth_deg == azimuth_deg; }
};

/// What the receiver tracked at one epoch, with or without a fix (an epoch with no
/// satellite is still an epoch). PDOP/HDOP are NaN when not reported.
struct SatEpoch {
  double t = 0.0;
  std::vector<SatObservation> sats;
  double pdop = kUnknown;
  double hdop = kUnknown;
  /// Mean C/N0 over the tracked satellites [dB-Hz]; 0 without satellites (what a receiver
  /// that tracks nothing reports as its average).
  double mean_cn0() const {
    if (sats.empty()) return 0.0;
    double s = 0.0;
    for (const auto& x : sats) s += x.cn0_dbhz;
    return s / static_cast<double>(sats.size());
  }
};

/// One two-way range from a UWB anchor. RSSI values are NaN when not recorded.
struct UwbRange {
  double t = 0.0;
  int anchor_id = 0;
  Eigen::Vector3d anchor_position = Eigen::Vector3d::Zero();  // same frame as the positions, m
  double range_m = 0.0;
  double rssi_dbm = kUnknown;
  double rssi_first_path_dbm = kUnknown;
};

/// Forward speed from an odometer or wheel ticks [m/s]; exactly 0 at rest.
struct SpeedSample {
  double t = 0.0;
  double speed_mps = 0.0;
};

/// Magnetic field in the sensor's axes [microtesla].
struct MagSample {
  double t = 0.0;
  Eigen::Vector3d field_ut = Eigen::Vector3d::Zero();
};

inline double GnssFix::std_horizontal() const {
  const double v = 0.5 * (cov(0, 0) + cov(1, 1));
  return v > 0.0 ? std::sqrt(v) : 0.0;
}

/// Every stream of one recording, each in time order (the readers and the replay check it).
struct SensorLog {
  std::vector<ImuSample> imu;
  std::vector<GnssFix> gnss;
  std::vector<SatEpoch> sat_epochs;
  std::vector<UwbRange> uwb;
  std::vector<SpeedSample> speed;
  std::vector<MagSample> mag;
};

}  // namespace ctxfuse::messages

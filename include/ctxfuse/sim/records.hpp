// The simulator's records: ground truth, the sensor outputs with their truth fields, and the
// labels a scorer reads (sim::TruthLog). Plain structs and the label names, apart from the
// simulator (sim/drive.hpp) and from the sensor messages a pipeline runs on
// (messages/sensors.hpp, which carry no truth), so that eval/ and the log files can use them
// without the simulator. Frames and units: sim/world.hpp.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "ctxfuse/messages/sensors.hpp"

namespace ctxfuse::sim {

/// Region labels of the region-recognition paper (A), zero-based.
enum class Region : std::uint8_t { outdoor = 0, transition = 1, indoor = 2 };
/// Scene labels of the scene-detection paper (B).
enum class Scene : std::uint8_t { open = 0, obstructed = 1, indoor = 2 };
inline constexpr int kRegionCount = 3;
inline constexpr int kSceneCount = 3;

inline const char* region_name(Region r) {
  switch (r) {
    case Region::outdoor: return "outdoor";
    case Region::transition: return "transition";
    case Region::indoor: return "indoor";
  }
  return "?";
}
inline const char* scene_name(Scene s) {
  switch (s) {
    case Scene::open: return "open";
    case Scene::obstructed: return "obstructed";
    case Scene::indoor: return "indoor";
  }
  return "?";
}

/// Ground truth at the IMU rate.
struct TruthSample {
  double t = 0.0;                                       // s since the start of the drive
  Eigen::Vector3d position = Eigen::Vector3d::Zero();   // ENU, m
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();   // ENU, m/s
  double roll = 0.0, pitch = 0.0, yaw = 0.0;            // rad; body FLU w.r.t. ENU, yaw CCW from east
  Eigen::Vector3d angular_rate = Eigen::Vector3d::Zero();    // body FLU, rad/s
  Eigen::Vector3d specific_force = Eigen::Vector3d::Zero();  // body FLU, m/s^2 (+9.81 on z at rest)
  double speed = 0.0;                                   // forward speed, m/s
  Region region = Region::outdoor;
  Scene scene = Scene::open;
  bool is_static = false;                               // vehicle exactly at rest
};

/// The simulated IMU's samples: rates in body FLU (gyro [rad/s], accel specific force [m/s^2]).
using ImuSample = messages::ImuSample;

/// The IMU's true errors: measured = (1 + scale) * true + bias + white noise, per axis.
struct ImuErrorTruth {
  std::vector<Eigen::Vector3d> gyro_bias;   // rad/s, one per ImuSample
  std::vector<Eigen::Vector3d> accel_bias;  // m/s^2, one per ImuSample
  Eigen::Vector3d gyro_scale = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_scale = Eigen::Vector3d::Zero();
};

/// One tracked satellite at one GNSS epoch.
struct SatObservation {
  double t = 0.0;
  int sat_id = 0;              // 1xx GPS-like, 2xx Galileo-like, 3xx BeiDou-like
  double elevation_deg = 0.0;
  double azimuth_deg = 0.0;    // clockwise from north
  double cn0_dbhz = 0.0;
  bool line_of_sight = true;   // truth: false when received diffracted/attenuated by buildings
};

/// One GNSS epoch (every epoch is listed, with or without a position fix).
struct GnssEpoch {
  double t = 0.0;
  bool has_fix = false;            // false with fewer than 4 satellites, and indoors (GnssConfig::indoor_fix_error_m)
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // fix, ENU m (zero without fix)
  double std_horizontal_m = 0.0;   // receiver-reported 1-sigma per horizontal axis
  double std_vertical_m = 0.0;
  int num_sats = 0;                // tracked satellites (all of them are used in the fix)
  double pdop = -1.0;              // -1 with fewer than 4 satellites
  double hdop = -1.0;
  double mean_cn0_dbhz = -1.0;     // -1 without satellites
  std::size_t first_sat = 0;       // this epoch's satellites are Drive::sats[first_sat, first_sat + num_sats)
  // Truth.
  Eigen::Vector3d error = Eigen::Vector3d::Zero();           // fix - true position (zero without fix)
  Eigen::Vector3d multipath_bias = Eigen::Vector3d::Zero();  // the correlated part of `error`
  Region region = Region::outdoor;
  Scene scene = Scene::open;
};

struct UwbRange {
  double t = 0.0;
  int anchor_id = 0;
  Eigen::Vector3d anchor_position = Eigen::Vector3d::Zero();  // ENU, m
  double range_m = 0.0;
  double rssi_dbm = 0.0;
  double rssi_first_path_dbm = 0.0;
  bool nlos = false;       // per-range label (truth)
  // Truth.
  double true_range_m = 0.0;
  double nlos_bias_m = 0.0;  // the bias added (0 in line of sight)
  int walls_crossed = 0;     // > 0: NLOS through walls; 0 with nlos: transient obstacle
};

struct SpeedSample {
  double t = 0.0;
  double speed_mps = 0.0;  // forward speed; exactly 0 at rest (wheel ticks stop)
};

struct MagSample {
  double t = 0.0;
  Eigen::Vector3d field_ut = Eigen::Vector3d::Zero();  // body FLU, microtesla
  double disturbance_ut = 0.0;  // truth: norm of the local anomaly added to the earth field
};

/// The label and true errors of one UWB range (matched to the range by time and anchor).
struct UwbRangeLabel {
  double t = 0.0;
  int anchor_id = 0;
  bool nlos = false;
  double true_range_m = 0.0;
  double nlos_bias_m = 0.0;
};

/// Whether one tracked satellite was received in line of sight.
struct SatLabel {
  double t = 0.0;
  int sat_id = 0;
  bool line_of_sight = true;
};

/// The true error of one GNSS fix.
struct FixLabel {
  double t = 0.0;
  Eigen::Vector3d error = Eigen::Vector3d::Zero();           // fix - truth, ENU m
  Eigen::Vector3d multipath_bias = Eigen::Vector3d::Zero();  // its correlated part
};

struct TruthLog {
  std::vector<sim::TruthSample> truth;  // strictly increasing in time
  std::vector<UwbRangeLabel> uwb;
  std::vector<SatLabel> sats;
  std::vector<FixLabel> fixes;  // empty when the log does not know them (only the simulator does)
};

}  // namespace ctxfuse::sim

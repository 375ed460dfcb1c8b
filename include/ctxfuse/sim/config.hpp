// Every knob of the simulated drive. Defaults describe a ~9 min drive from the street
// through a covered approach into a parking garage and back out, with the region shares of
// the region-recognition paper (outdoor 34.3 %, transition 19.1 %, indoor 46.6 %) and sensor
// figures typical of an automotive MEMS IMU, a low-cost multi-constellation receiver and a
// DW1000-class UWB system.
#pragma once

#include <array>
#include <cstdint>

namespace ctxfuse::sim {

struct RouteConfig {
  double duration_s = 540.0;  // target length of the drive; met to within about a second
  /// Target time shares of outdoor, transition, indoor (sum to 1). The route's elastic
  /// lengths are solved so that the drive spends these shares in each region.
  std::array<double, 3> region_shares{0.343, 0.191, 0.466};
  double outdoor_speed_mps = 6.0;
  double transition_speed_mps = 3.0;
  double indoor_speed_mps = 2.5;
  int indoor_laps = 3;
  double max_accel_mps2 = 1.0;  // peak of the raised-cosine speed changes
  double curvature_ramp_m = 4.0;  // curvature changes linearly over this length (no jerk steps)
  // Static stops (vehicle exactly at rest): start, traffic light, barrier gate, parking, end.
  double initial_static_s = 10.0;
  double traffic_stop_s = 6.0;
  double gate_stop_s = 6.0;
  double parking_stop_s = 15.0;
  double final_static_s = 10.0;
  // Sky geometry of the site as GNSS sees it (UWB walls are unaffected).
  /// The approach's buildings are this tall at its street end and rise linearly to the full
  /// 12 m at the garage door: the covered approach opens onto the street and closes gradually
  /// (a single tall canyon over its whole length would leave only near-axis satellites).
  double approach_open_end_height_m = 3.0;
  /// Clear height of the garage doorway (10 m wide): satellites low in the west stay visible
  /// through it for the first metres inside.
  double garage_door_height_m = 3.0;
  /// UWB anchors in the covered approach (two, 8 m from the garage door). Without them every
  /// anchor is inside the garage and the approach sees the garage's anchors only through the
  /// doorway or the garage wall (scenario "paper", sim/scenarios.hpp).
  bool approach_uwb_anchors = true;
};

/// MEMS IMU error model per axis: white noise given as a density, first-order Gauss-Markov
/// bias started from its stationary distribution, constant scale-factor error.
struct ImuConfig {
  double rate_hz = 100.0;
  double gyro_noise_density = 8.7e-5;     // rad/s/sqrt(Hz)  (0.005 deg/s/sqrt(Hz), 0.3 deg/sqrt(h))
  double gyro_bias_sigma = 8.7e-5;        // rad/s           (0.005 deg/s, 18 deg/h)
  double gyro_bias_tau_s = 300.0;
  double gyro_scale_sigma = 1.0e-3;       // dimensionless   (1000 ppm)
  double accel_noise_density = 1.0e-3;    // m/s^2/sqrt(Hz)  (100 ug/sqrt(Hz))
  double accel_bias_sigma = 0.02;         // m/s^2           (2 mg)
  double accel_bias_tau_s = 300.0;
  double accel_scale_sigma = 1.0e-3;
};

/// Index of GnssConfig's per-environment arrays.
enum class GnssEnvironment : int { open = 0, obstructed = 1, transition = 2 };

struct GnssConfig {
  double rate_hz = 1.0;
  double elevation_mask_deg = 5.0;
  double tracking_threshold_dbhz = 25.0;  // weaker signals are not tracked (not counted)
  double cn0_horizon_dbhz = 33.0;         // line-of-sight C/N0 at 0 deg elevation ...
  double cn0_zenith_dbhz = 48.0;          // ... and at 90 deg, linear in sin(elevation)
  double cn0_satellite_sigma_db = 1.5;    // fixed per-satellite offset (power, antenna gain)
  double cn0_noise_los_db = 1.0;          // epoch-to-epoch C/N0 noise, line of sight
  double cn0_noise_nlos_db = 3.0;         // diffracted / reflected signals fluctuate more
  double diffraction_band_deg = 8.0;      // satellites this far below a building edge arrive diffracted
  double diffraction_loss_min_db = 6.0;
  double diffraction_loss_max_db = 14.0;
  /// User-equivalent range error (m), per environment {open, obstructed street, transition}:
  /// horizontal white error has per-axis std uere * HDOP / sqrt(2), vertical uere * VDOP.
  std::array<double, 3> uere_m{2.0, 2.5, 2.5};
  /// Multipath bias per axis (m): Gauss-Markov, std per environment, correlation time below.
  std::array<double, 3> multipath_sigma_m{0.0, 1.5, 1.5};
  double multipath_tau_s = 20.0;
  // Sky: three MEO constellations (GPS, Galileo, BeiDou-MEO), ~28 satellites above 5 deg.
  double latitude_deg = 24.85;   // Kunming, where the region paper's drive took place
  double longitude_deg = 102.85;
  double sky_start_s = 0.0;      // orbit epoch offset: moves the sky to another time of day
  double antenna_height_m = 1.5;  // above ground: sets what the garage doorway lets through
  /// Slow C/N0 fading (multipath interference, body shadowing): a Gauss-Markov process per
  /// satellite with this std per environment {open, obstructed street, transition/indoor} and
  /// correlation time, added on top of the white epoch noise.
  std::array<double, 3> cn0_fading_sigma_db{1.0, 2.5, 3.0};
  double cn0_fading_tau_s = 3.0;
  /// Roadside obstructions on the open outdoor streets (single tall buildings, tree rows):
  /// this many stretches of this length, centred at points drawn uniformly along the open
  /// street route, each hiding one side of the sky below an edge elevation drawn uniformly
  /// in [min, max] (towards the perpendicular; lower at oblique azimuths, as a street wall),
  /// with extra attenuation (foliage) on every signal inside the stretch.
  int roadside_obstruction_count = 6;
  double roadside_obstruction_length_m = 30.0;
  double roadside_obstruction_edge_min_deg = 25.0;
  double roadside_obstruction_edge_max_deg = 60.0;
  double roadside_obstruction_attenuation_db = 2.0;
  /// Signals reaching the receiver under the garage roof through the doorway lose this much
  /// at the door (edge diffraction, door frame) plus this much per metre travelled under the
  /// roof (scattering by parked cars, pillars): a few weak satellites for some metres inside.
  double doorway_loss_db = 3.0;
  double indoor_loss_db_per_m = 0.5;
  /// Indoor fixes, off by default (0). Some receivers keep reporting a position under a roof
  /// (coasting on their own motion model, or fixing on a few reflected signals); that is the
  /// case where a region-aware filter has a wrong-side sensor to leave out. When > 0, every
  /// indoor epoch has a fix whose horizontal error per axis is a Gauss-Markov process of this
  /// std (m; correlation time multipath_tau_s, the same unit process as the multipath, so the
  /// error is continuous across the door), vertical likewise, and the receiver reports
  /// indoor_fix_reported_ratio times that std as its 1-sigma (below 1: over-confident).
  double indoor_fix_error_m = 0.0;
  double indoor_fix_reported_ratio = 1.0;
};

struct UwbConfig {
  double rate_hz = 10.0;
  double tag_height_m = 1.0;
  double range_noise_m = 0.10;
  double nlos_bias_min_m = 0.5;  // NLOS bias drawn uniformly per NLOS episode ...
  double nlos_bias_max_m = 2.0;
  double nlos_extra_noise_m = 0.30;  // ... with this extra white noise
  double max_range_los_m = 60.0;
  double max_range_nlos_m = 30.0;
  double dropout_at_zero = 0.02;  // dropout probability grows quadratically with distance ...
  double dropout_at_max = 0.60;   // ... from this at 0 m to this at the maximum range
  /// Transient NLOS (parked cars, people, other vehicles) on geometrically clear lines, per
  /// region {outdoor, transition, indoor}: stationary probability of a two-state Markov chain.
  std::array<double, 3> transient_nlos_probability{0.05, 0.15, 0.10};
  double transient_nlos_mean_duration_s = 1.5;
  // Received power, DW1000-like log-distance model.
  double rssi_at_1m_dbm = -62.0;
  double rssi_noise_db = 1.0;
  double wall_loss_min_db = 3.0;
  double wall_loss_max_db = 10.0;
  double first_path_gap_los_db = 1.5;   // rssi - rssi_fp in line of sight (plus |N(0,1)|)
  double first_path_gap_nlos_min_db = 6.0;
  double first_path_gap_nlos_max_db = 12.0;
  /// The garage's outer walls (thick concrete) opaque to UWB. Off: a range whose line crosses
  /// a wall is NLOS with a bias drawn in [nlos_bias_min_m, nlos_bias_max_m]. On: between a point
  /// inside the garage and one outside it, when the straight line does not pass through the
  /// doorway, the first path to arrive is the one diffracted round the nearer door jamb, so the
  /// range is that path's length (the bias is its excess over the straight line, pure
  /// geometry); it is NLOS, limited by max_range_nlos_m on the path length.
  bool garage_walls_opaque = false;
};

struct SpeedConfig {
  double rate_hz = 10.0;
  double noise_mps = 0.05;
  double scale_sigma = 0.01;  // wheel-radius error, drawn once per drive
};

struct MagnetometerConfig {
  double rate_hz = 10.0;
  double noise_ut = 0.2;
  double field_ut = 47.0;  // earth field at the site
  double inclination_deg = 40.0;
  double declination_deg = -1.5;
  /// Local anomalies (steel, rebar, cars): Gaussian blobs of this spatial scale whose peak
  /// amplitude is drawn per blob, stronger inside the garage than near it.
  double anomaly_length_m = 4.0;
  double anomaly_indoor_ut = 10.0;
  double anomaly_near_ut = 4.0;
  int anomaly_count = 150;
};

struct DriveConfig {
  std::uint64_t seed = 1;
  RouteConfig route;
  ImuConfig imu;
  GnssConfig gnss;
  UwbConfig uwb;
  SpeedConfig speed;
  MagnetometerConfig magnetometer;
};

}  // namespace ctxfuse::sim

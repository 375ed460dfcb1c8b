// simulate_drive(): the whole scenario in plain structs of std::vectors. Deterministic from
// DriveConfig::seed; every sensor draws from its own sub-stream (see random.hpp).
// Frames and units: see world.hpp (ENU navigation frame, FLU body frame, yaw CCW from east).
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "ctxfuse/sim/config.hpp"
#include "ctxfuse/sim/random.hpp"
#include "ctxfuse/sim/records.hpp"
#include "ctxfuse/sim/route.hpp"
#include "ctxfuse/sim/sky.hpp"
#include "ctxfuse/sim/world.hpp"

namespace ctxfuse::sim {

/// Truth of one roadside obstruction (GnssConfig::roadside_obstruction_*): within radius_m of
/// centre, satellites on the blocked side of the road axis are hidden below
/// atan(tan(edge) * |sin(relative azimuth)|), arriving diffracted within the diffraction band.
struct RoadsideObstruction {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  double radius_m = 0.0;
  double axis_yaw_rad = 0.0;  // road direction, ENU yaw
  bool left_side = true;      // blocked side, looking along axis_yaw_rad
  double edge_deg = 0.0;      // edge elevation perpendicular to the road

  bool covers(const Eigen::Vector2d& p) const { return (p - centre).norm() <= radius_m; }
  /// Edge elevation (deg) at this satellite azimuth (deg clockwise from north); 0 on the open side.
  double mask_elevation_deg(double azimuth_deg) const {
    const double sat_yaw = std::numbers::pi / 2.0 - azimuth_deg * std::numbers::pi / 180.0;
    const double s = std::sin(sat_yaw - axis_yaw_rad);  // > 0: satellite to the left of the road
    if ((s > 0.0) != left_side) return 0.0;
    return std::atan(std::tan(edge_deg * std::numbers::pi / 180.0) * std::abs(s)) * 180.0 / std::numbers::pi;
  }
};

struct Drive {
  DriveConfig config;
  Route route;  // includes the World (regions, canyons, walls, anchors)
  std::vector<TruthSample> truth;
  std::vector<ImuSample> imu;
  ImuErrorTruth imu_errors;
  std::vector<GnssEpoch> gnss;
  std::vector<SatObservation> sats;
  std::vector<RoadsideObstruction> roadside_obstructions;  // truth of the GNSS sky obstructions
  std::vector<UwbRange> uwb;
  std::vector<SpeedSample> speed;
  double speed_scale_error = 0.0;  // truth: measured = (1 + speed_scale_error) * true + noise
  std::vector<MagSample> mag;

  const World& world() const { return route.world; }
  double duration() const { return route.duration(); }
  /// The satellites tracked at one epoch (elevation, azimuth, C/N0), for scene features.
  std::span<const SatObservation> satellites_of(const GnssEpoch& e) const {
    return std::span<const SatObservation>(sats).subspan(e.first_sat, static_cast<std::size_t>(e.num_sats));
  }
  /// Fraction of truth samples in each region (outdoor, transition, indoor).
  std::array<double, 3> region_shares() const {
    std::array<double, 3> s{};
    for (const auto& x : truth) s[static_cast<std::size_t>(x.region)] += 1.0;
    for (auto& v : s) v /= std::max<double>(1.0, static_cast<double>(truth.size()));
    return s;
  }
};

/// Earth field in ENU (microtesla) from total intensity, inclination (down positive) and
/// declination (east of north positive).
inline Eigen::Vector3d earth_field_enu(const MagnetometerConfig& c) {
  const double d2r = std::numbers::pi / 180.0;
  const double h = c.field_ut * std::cos(c.inclination_deg * d2r);
  return {h * std::sin(c.declination_deg * d2r), h * std::cos(c.declination_deg * d2r), -c.field_ut * std::sin(c.inclination_deg * d2r)};
}

namespace detail {


inline void check_config(const DriveConfig& c) {
  auto bad = [](const std::string& what) { throw std::invalid_argument("sim DriveConfig: " + what); };
  auto rate_ok = [](double r) { return r >= 0.1 && r <= 1000.0; };
  if (!rate_ok(c.imu.rate_hz)) bad("imu.rate_hz must be within [0.1, 1000]");
  if (!rate_ok(c.gnss.rate_hz)) bad("gnss.rate_hz must be within [0.1, 1000]");
  if (!rate_ok(c.uwb.rate_hz)) bad("uwb.rate_hz must be within [0.1, 1000]");
  if (!rate_ok(c.speed.rate_hz)) bad("speed.rate_hz must be within [0.1, 1000]");
  if (!rate_ok(c.magnetometer.rate_hz)) bad("magnetometer.rate_hz must be within [0.1, 1000]");
  auto nonneg = [&](double v, const char* name) {
    if (!(v >= 0.0 && v < 1e6)) bad(std::string(name) + " must be finite and >= 0");
  };
  nonneg(c.imu.gyro_noise_density, "imu.gyro_noise_density");
  nonneg(c.imu.gyro_bias_sigma, "imu.gyro_bias_sigma");
  nonneg(c.imu.gyro_scale_sigma, "imu.gyro_scale_sigma");
  nonneg(c.imu.accel_noise_density, "imu.accel_noise_density");
  nonneg(c.imu.accel_bias_sigma, "imu.accel_bias_sigma");
  nonneg(c.imu.accel_scale_sigma, "imu.accel_scale_sigma");
  if (!(c.imu.gyro_bias_tau_s > 0.0) || !(c.imu.accel_bias_tau_s > 0.0)) bad("imu bias tau must be > 0");
  if (!(c.gnss.multipath_tau_s > 0.0)) bad("gnss.multipath_tau_s must be > 0");
  for (double v : c.gnss.uere_m) nonneg(v, "gnss.uere_m");
  for (double v : c.gnss.multipath_sigma_m) nonneg(v, "gnss.multipath_sigma_m");
  for (double v : c.gnss.cn0_fading_sigma_db) nonneg(v, "gnss.cn0_fading_sigma_db");
  if (!(c.gnss.cn0_fading_tau_s > 0.0)) bad("gnss.cn0_fading_tau_s must be > 0");
  if (c.gnss.roadside_obstruction_count < 0 || c.gnss.roadside_obstruction_count > 1000)
    bad("gnss.roadside_obstruction_count must be within [0, 1000]");
  if (!(c.gnss.roadside_obstruction_length_m >= 0.0)) bad("gnss.roadside_obstruction_length_m must be >= 0");
  if (!(c.gnss.roadside_obstruction_edge_min_deg >= 0.0 && c.gnss.roadside_obstruction_edge_min_deg <= c.gnss.roadside_obstruction_edge_max_deg &&
        c.gnss.roadside_obstruction_edge_max_deg < 90.0))
    bad("gnss.roadside_obstruction_edge_min/max_deg must satisfy 0 <= min <= max < 90");
  nonneg(c.gnss.roadside_obstruction_attenuation_db, "gnss.roadside_obstruction_attenuation_db");
  nonneg(c.gnss.doorway_loss_db, "gnss.doorway_loss_db");
  nonneg(c.gnss.indoor_loss_db_per_m, "gnss.indoor_loss_db_per_m");
  nonneg(c.gnss.indoor_fix_error_m, "gnss.indoor_fix_error_m");
  if (!(c.gnss.indoor_fix_reported_ratio > 0.0 && c.gnss.indoor_fix_reported_ratio <= 100.0))
    bad("gnss.indoor_fix_reported_ratio must be within (0, 100]");
  if (!(c.gnss.antenna_height_m >= 0.0 && c.gnss.antenna_height_m <= 10.0)) bad("gnss.antenna_height_m must be within [0, 10] m");
  nonneg(c.uwb.range_noise_m, "uwb.range_noise_m");
  nonneg(c.uwb.nlos_extra_noise_m, "uwb.nlos_extra_noise_m");
  if (!(c.uwb.nlos_bias_min_m >= 0.0 && c.uwb.nlos_bias_max_m >= c.uwb.nlos_bias_min_m))
    bad("uwb.nlos_bias_min_m/max_m must satisfy 0 <= min <= max");
  if (!(c.uwb.max_range_los_m > 0.0 && c.uwb.max_range_nlos_m > 0.0)) bad("uwb max ranges must be > 0");
  for (double p : c.uwb.transient_nlos_probability)
    if (!(p >= 0.0 && p < 1.0)) bad("uwb.transient_nlos_probability must be within [0, 1)");
  if (!(c.uwb.transient_nlos_mean_duration_s > 0.0)) bad("uwb.transient_nlos_mean_duration_s must be > 0");
  if (!(c.uwb.dropout_at_zero >= 0.0 && c.uwb.dropout_at_max <= 1.0 && c.uwb.dropout_at_zero <= c.uwb.dropout_at_max))
    bad("uwb dropout probabilities must satisfy 0 <= at_zero <= at_max <= 1");
  nonneg(c.speed.noise_mps, "speed.noise_mps");
  nonneg(c.speed.scale_sigma, "speed.scale_sigma");
  nonneg(c.magnetometer.noise_ut, "magnetometer.noise_ut");
  if (c.magnetometer.anomaly_count < 0 || c.magnetometer.anomaly_count > 10000) bad("magnetometer.anomaly_count must be within [0, 10000]");
  if (!(c.magnetometer.anomaly_length_m > 0.0)) bad("magnetometer.anomaly_length_m must be > 0");
}

/// Sample times k / rate for k = 0 .. while t <= duration (no accumulated rounding).
template <class F>
void for_each_epoch(double rate, double duration, F&& f) {
  for (long k = 0;; ++k) {
    const double t = static_cast<double>(k) / rate;
    if (t > duration) break;
    f(t);
  }
}

inline TruthSample make_truth(const Route& route, const KinematicState& st) {
  TruthSample s;
  s.t = st.t;
  s.position = st.position;
  s.velocity = st.velocity;
  s.yaw = st.yaw;
  s.angular_rate = st.angular_rate_body;
  s.specific_force = st.specific_force_body;
  s.speed = st.speed;
  const Eigen::Vector2d p2 = st.position.head<2>();
  s.region = route.world.region_at(p2);
  s.scene = route.world.scene_at(p2);
  s.is_static = st.is_static;
  return s;
}

inline void simulate_imu(Drive& d) {
  const auto& c = d.config.imu;
  Rng rng(d.config.seed, Stream::imu);
  auto& err = d.imu_errors;
  for (int i = 0; i < 3; ++i) {
    err.gyro_scale[i] = c.gyro_scale_sigma * rng.normal();
    err.accel_scale[i] = c.accel_scale_sigma * rng.normal();
  }
  const GaussMarkov gyro_gm{c.gyro_bias_sigma, c.gyro_bias_tau_s};
  const GaussMarkov accel_gm{c.accel_bias_sigma, c.accel_bias_tau_s};
  Eigen::Vector3d bg, ba;
  for (int i = 0; i < 3; ++i) {
    bg[i] = gyro_gm.start(rng);
    ba[i] = accel_gm.start(rng);
  }
  const double dt = 1.0 / c.rate_hz;
  const double gyro_white = c.gyro_noise_density * std::sqrt(c.rate_hz);
  const double accel_white = c.accel_noise_density * std::sqrt(c.rate_hz);
  d.imu.reserve(d.truth.size());
  err.gyro_bias.reserve(d.truth.size());
  err.accel_bias.reserve(d.truth.size());
  for (std::size_t k = 0; k < d.truth.size(); ++k) {
    const auto& tr = d.truth[k];
    if (k > 0)
      for (int i = 0; i < 3; ++i) {
        bg[i] = gyro_gm.step(bg[i], dt, rng);
        ba[i] = accel_gm.step(ba[i], dt, rng);
      }
    ImuSample s;
    s.t = tr.t;
    for (int i = 0; i < 3; ++i) {
      s.gyro[i] = (1.0 + err.gyro_scale[i]) * tr.angular_rate[i] + bg[i] + gyro_white * rng.normal();
      s.accel[i] = (1.0 + err.accel_scale[i]) * tr.specific_force[i] + ba[i] + accel_white * rng.normal();
    }
    d.imu.push_back(s);
    err.gyro_bias.push_back(bg);
    err.accel_bias.push_back(ba);
  }
}

inline GnssEnvironment gnss_environment(Region r, Scene s) {
  if (r == Region::transition) return GnssEnvironment::transition;
  return s == Scene::open ? GnssEnvironment::open : GnssEnvironment::obstructed;
}

inline void simulate_gnss(Drive& d) {
  const auto& c = d.config.gnss;
  Rng rng(d.config.seed, Stream::gnss);
  const Sky sky(c.latitude_deg, c.longitude_deg, c.sky_start_s);
  const World& world = d.route.world;
  // Fixed per-satellite C/N0 offsets, drawn up front for every id so that they do not depend
  // on which satellites happen to be visible.
  std::array<double, 400> sat_offset{};
  for (auto& o : sat_offset) o = c.cn0_satellite_sigma_db * rng.normal();
  const GaussMarkov mp_gm{1.0, c.multipath_tau_s};  // unit std, scaled per environment
  Eigen::Vector3d mp_unit;
  for (int i = 0; i < 3; ++i) mp_unit[i] = mp_gm.start(rng);
  const GaussMarkov fading_gm{1.0, c.cn0_fading_tau_s};  // unit std, scaled per environment
  std::array<double, 400> fading_unit{};
  for (auto& f : fading_unit) f = fading_gm.start(rng);
  // Roadside obstructions: centres drawn uniformly over the open-street part of the route
  // (sampled every 0.5 s of drive time, i.e. weighted by time spent there).
  d.roadside_obstructions.clear();
  {
    std::vector<KinematicState> open_route;
    for (double t = 0.0; t < d.route.duration(); t += 0.5) {
      const KinematicState st = d.route.state_at(t);
      if (world.scene_at(Eigen::Vector2d(st.position.head<2>())) == Scene::open) open_route.push_back(st);
    }
    for (int k = 0; k < c.roadside_obstruction_count; ++k) {
      const double pick = rng.uniform(), side = rng.uniform(), edge = rng.uniform();
      if (open_route.empty()) continue;
      const auto& st = open_route[std::min(open_route.size() - 1, static_cast<std::size_t>(pick * static_cast<double>(open_route.size())))];
      d.roadside_obstructions.push_back({st.position.head<2>(), 0.5 * c.roadside_obstruction_length_m, st.yaw, side < 0.5,
                                         c.roadside_obstruction_edge_min_deg +
                                             (c.roadside_obstruction_edge_max_deg - c.roadside_obstruction_edge_min_deg) * edge});
    }
  }
  const Doorway& door = world.garage_door;
  const double dt = 1.0 / c.rate_hz;
  std::vector<LookAngle> sky_now;
  std::vector<Eigen::Vector3d> los_used;
  for_each_epoch(c.rate_hz, d.route.duration(), [&](double t) {
    const KinematicState st = d.route.state_at(t);
    const Eigen::Vector2d p2 = st.position.head<2>();
    GnssEpoch e;
    e.t = t;
    e.region = world.region_at(p2);
    e.scene = world.scene_at(p2);
    e.first_sat = d.sats.size();
    for (int i = 0; i < 3; ++i) mp_unit[i] = mp_gm.step(mp_unit[i], dt, rng);
    for (auto& f : fading_unit) f = fading_gm.step(f, dt, rng);
    sky.visible(t, c.elevation_mask_deg, sky_now);
    const StreetCanyon* canyon = world.canyon_at(p2);
    const RoadsideObstruction* roadside = nullptr;
    if (e.scene == Scene::open)
      for (const auto& o : d.roadside_obstructions)
        if (o.covers(p2)) {
          roadside = &o;
          break;
        }
    const double fading_sigma = c.cn0_fading_sigma_db[static_cast<std::size_t>(
        e.region == Region::indoor ? GnssEnvironment::transition : gnss_environment(e.region, e.scene))];
    // Indoors, the doorway's centre seen from here decides which canyon the escaping ray meets.
    const StreetCanyon* outside_canyon = world.canyon_at(Eigen::Vector2d(0.5 * (door.a + door.b) + Eigen::Vector2d(-0.5, 0.0)));
    los_used.clear();
    double cn0_sum = 0.0;
    for (const auto& la : sky_now) {
      // Draws happen for every satellite above the mask whatever its fate, so the random
      // sequence does not depend on the geometry.
      const double noise_unit = rng.normal();
      const double loss_unit = rng.uniform();
      bool los = true;
      double loss = 0.0;
      auto obstruct = [&](double edge_deg) {  // false: hidden
        if (la.elevation_deg < edge_deg - c.diffraction_band_deg) return false;
        if (la.elevation_deg < edge_deg && los) {
          los = false;
          loss += c.diffraction_loss_min_db + (c.diffraction_loss_max_db - c.diffraction_loss_min_db) * loss_unit;
        }
        return true;
      };
      if (e.region == Region::indoor) {
        // The roof hides the sky except through the doorway: the horizontal ray towards the
        // satellite must leave through the opening, below its top (or within the diffraction
        // band above it), and then clear the approach's buildings at the door.
        const double az = la.azimuth_deg * std::numbers::pi / 180.0;
        const Eigen::Vector2d dir(std::sin(az), std::cos(az));
        const Eigen::Vector2d span = door.b - door.a;
        const double denom = dir.x() * span.y() - dir.y() * span.x();
        if (std::abs(denom) < 1e-12) continue;
        const Eigen::Vector2d rel = door.a - p2;
        const double run = (rel.x() * span.y() - rel.y() * span.x()) / denom;  // metres under the roof
        const double u = (rel.x() * dir.y() - rel.y() * dir.x()) / denom;
        if (!(run > 0.0) || u < 0.0 || u > 1.0 || door.height_m <= c.antenna_height_m) continue;
        const double top_deg = std::atan2(door.height_m - c.antenna_height_m, run) * 180.0 / std::numbers::pi;
        // The lintel hides what is above the opening (diffracted just above its edge).
        if (la.elevation_deg > top_deg + c.diffraction_band_deg) continue;
        if (la.elevation_deg > top_deg) {
          los = false;
          loss += c.diffraction_loss_min_db + (c.diffraction_loss_max_db - c.diffraction_loss_min_db) * loss_unit;
        }
        if (outside_canyon && !obstruct(outside_canyon->mask_elevation_deg(la.azimuth_deg, door.a))) continue;
        loss += c.doorway_loss_db + c.indoor_loss_db_per_m * run + (outside_canyon ? outside_canyon->extra_attenuation_db : 0.0);
      } else if (canyon) {
        if (!obstruct(canyon->mask_elevation_deg(la.azimuth_deg, p2))) continue;
        loss += canyon->extra_attenuation_db;
      } else if (roadside) {
        if (!obstruct(roadside->mask_elevation_deg(la.azimuth_deg))) continue;
        loss += c.roadside_obstruction_attenuation_db;
      }
      const double sin_el = std::sin(la.elevation_deg * std::numbers::pi / 180.0);
      const double cn0 = c.cn0_horizon_dbhz + (c.cn0_zenith_dbhz - c.cn0_horizon_dbhz) * sin_el +
                         sat_offset[static_cast<std::size_t>(la.sat_id) % sat_offset.size()] - loss +
                         (los ? c.cn0_noise_los_db : c.cn0_noise_nlos_db) * noise_unit +
                         fading_sigma * fading_unit[static_cast<std::size_t>(la.sat_id) % fading_unit.size()];
      if (cn0 < c.tracking_threshold_dbhz) continue;
      d.sats.push_back({t, la.sat_id, la.elevation_deg, la.azimuth_deg, cn0, los});
      los_used.push_back(la.los_enu);
      cn0_sum += cn0;
    }
    e.num_sats = static_cast<int>(los_used.size());
    if (e.num_sats > 0) e.mean_cn0_dbhz = cn0_sum / e.num_sats;
    double pdop = 0, hdop = 0, vdop = 0;
    const bool geometry_ok = dilution_of_precision(los_used, pdop, hdop, vdop);
    if (geometry_ok) {
      e.pdop = pdop;
      e.hdop = hdop;
    }
    const auto env = static_cast<std::size_t>(gnss_environment(e.region, e.scene));
    const Eigen::Vector3d white = rng.normals<3>();
    if (geometry_ok && e.region != Region::indoor) {
      const double sh = c.uere_m[env] * hdop / std::sqrt(2.0), sv = c.uere_m[env] * vdop;
      const double mp = c.multipath_sigma_m[env];
      e.multipath_bias = mp * mp_unit;
      e.error = e.multipath_bias + Eigen::Vector3d(sh * white.x(), sh * white.y(), sv * white.z());
      e.has_fix = true;
      e.position = st.position + e.error;
      e.std_horizontal_m = std::sqrt(sh * sh + mp * mp);
      e.std_vertical_m = std::sqrt(sv * sv + mp * mp);
    } else if (e.region == Region::indoor && c.indoor_fix_error_m > 0.0) {
      // No new random draws: the default drive's sequence stays what it was.
      e.multipath_bias = c.indoor_fix_error_m * mp_unit;
      e.error = e.multipath_bias;
      e.has_fix = true;
      e.position = st.position + e.error;
      e.std_horizontal_m = e.std_vertical_m = c.indoor_fix_reported_ratio * c.indoor_fix_error_m;
    }
    d.gnss.push_back(e);
  });
}

/// With the garage's outer walls opaque to UWB: the length of the first path between a and b
/// when one is inside the garage and the other outside and the straight line does not pass
/// through the doorway, i.e. the path bent round the nearer door jamb (a vertical edge: the
/// horizontal legs add up, the height difference is covered along the way). Nothing when the
/// two are on the same side or the straight line passes through the opening.
inline std::optional<double> doorway_path_length(const World& world, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector2d a2 = a.head<2>(), b2 = b.head<2>();
  if ((world.region_at(a2) == Region::indoor) == (world.region_at(b2) == Region::indoor)) return std::nullopt;
  if (segments_cross(a2, b2, world.garage_door.a, world.garage_door.b)) return std::nullopt;
  const double dz = a.z() - b.z();
  double path = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector2d& jamb : {world.garage_door.a, world.garage_door.b}) {
    const double horizontal = (a2 - jamb).norm() + (jamb - b2).norm();
    path = std::min(path, std::sqrt(horizontal * horizontal + dz * dz));
  }
  return path;
}

inline void simulate_uwb(Drive& d) {
  const auto& c = d.config.uwb;
  Rng rng(d.config.seed, Stream::uwb);
  const World& world = d.route.world;
  const std::size_t n = world.anchors.size();
  std::vector<bool> transient(n, false);
  std::vector<bool> was_nlos(n, false);
  std::vector<double> episode_bias(n, 0.0);
  const double dt = 1.0 / c.rate_hz;
  const double p_exit = std::min(1.0, dt / c.transient_nlos_mean_duration_s);
  for_each_epoch(c.rate_hz, d.route.duration(), [&](double t) {
    const KinematicState st = d.route.state_at(t);
    const Eigen::Vector2d p2 = st.position.head<2>();
    const Eigen::Vector3d tag(st.position.x(), st.position.y(), c.tag_height_m);
    const auto region = static_cast<std::size_t>(world.region_at(p2));
    // Two-state chain with stationary probability p: enter with p_exit * p / (1 - p).
    const double p = c.transient_nlos_probability[region];
    const double p_enter = std::min(1.0, p_exit * p / (1.0 - p));
    for (std::size_t a = 0; a < n; ++a) {
      const auto& anchor = world.anchors[a];
      // Fixed number of draws per anchor and epoch (see simulate_gnss).
      const double u_chain = rng.uniform(), u_drop = rng.uniform(), u_bias = rng.uniform(), u_loss = rng.uniform();
      const double u_gap = rng.uniform(), n_range = rng.normal(), n_extra = rng.normal(), n_rssi = rng.normal(),
                   n_gap = rng.normal();
      transient[a] = transient[a] ? !(u_chain < p_exit) : (u_chain < p_enter);
      const Eigen::Vector2d a2 = anchor.position.head<2>();
      int walls = world.walls_crossed(p2, a2);
      const double true_range = (anchor.position - tag).norm();
      // Opaque garage walls: the first path between inside and outside is the one bent round
      // a door jamb (vertical edge), unless the straight line passes through the opening.
      double door_excess = 0.0;
      bool door_path = false;
      if (c.garage_walls_opaque) {
        if (const auto path = doorway_path_length(world, anchor.position, tag)) {
          door_excess = *path - true_range;
          door_path = true;
          walls = std::max(walls, 1);
        }
      }
      const bool nlos = walls > 0 || transient[a];
      if (nlos && !was_nlos[a]) episode_bias[a] = c.nlos_bias_min_m + (c.nlos_bias_max_m - c.nlos_bias_min_m) * u_bias;
      was_nlos[a] = nlos;
      const double path_length = true_range + door_excess;
      const double max_range = nlos ? c.max_range_nlos_m : c.max_range_los_m;
      if (path_length > max_range) continue;
      const double x = path_length / max_range;
      if (u_drop < c.dropout_at_zero + (c.dropout_at_max - c.dropout_at_zero) * x * x) continue;
      UwbRange r;
      r.t = t;
      r.anchor_id = anchor.id;
      r.anchor_position = anchor.position;
      r.true_range_m = true_range;
      r.nlos = nlos;
      r.walls_crossed = walls;
      r.nlos_bias_m = door_path ? door_excess : nlos ? episode_bias[a] : 0.0;
      r.range_m = true_range + r.nlos_bias_m + c.range_noise_m * n_range + (nlos ? c.nlos_extra_noise_m * n_extra : 0.0);
      const double wall_loss = walls > 0 ? walls * (c.wall_loss_min_db + (c.wall_loss_max_db - c.wall_loss_min_db) * u_loss) : 0.0;
      r.rssi_dbm = c.rssi_at_1m_dbm - 20.0 * std::log10(std::max(1.0, path_length)) - wall_loss + c.rssi_noise_db * n_rssi;
      const double gap = nlos ? c.first_path_gap_nlos_min_db + (c.first_path_gap_nlos_max_db - c.first_path_gap_nlos_min_db) * u_gap
                              : c.first_path_gap_los_db + std::abs(n_gap);
      r.rssi_first_path_dbm = r.rssi_dbm - gap;
      d.uwb.push_back(r);
    }
  });
}

inline void simulate_speed(Drive& d) {
  const auto& c = d.config.speed;
  Rng rng(d.config.seed, Stream::speed);
  const double scale = c.scale_sigma * rng.normal();
  d.speed_scale_error = scale;
  for_each_epoch(c.rate_hz, d.route.duration(), [&](double t) {
    const KinematicState st = d.route.state_at(t);
    const double noise = c.noise_mps * rng.normal();
    const double v = st.speed == 0.0 ? 0.0 : std::max(0.0, (1.0 + scale) * st.speed + noise);
    d.speed.push_back({t, v});
  });
}

inline void simulate_magnetometer(Drive& d) {
  const auto& c = d.config.magnetometer;
  Rng rng(d.config.seed, Stream::magnetometer);
  const World& world = d.route.world;
  struct Anomaly {
    Eigen::Vector2d at;
    Eigen::Vector3d amplitude;
  };
  // Anomalies scattered over the garage and a 20 m band around it and the approach.
  double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
  for (const auto* poly : {&world.indoor, &world.transition})
    for (const auto& v : poly->vertices) {
      x0 = std::min(x0, v.x()); x1 = std::max(x1, v.x());
      y0 = std::min(y0, v.y()); y1 = std::max(y1, v.y());
    }
  std::vector<Anomaly> anomalies;
  for (int i = 0; i < c.anomaly_count; ++i) {
    Eigen::Vector2d at;
    at.x() = rng.uniform(x0 - 20.0, x1 + 20.0);
    at.y() = rng.uniform(y0 - 20.0, y1 + 20.0);
    const double amp = world.region_at(at) == Region::indoor ? c.anomaly_indoor_ut : c.anomaly_near_ut;
    anomalies.push_back({at, amp * rng.normals<3>()});
  }
  const Eigen::Vector3d earth = earth_field_enu(c);
  const double two_l2 = 2.0 * c.anomaly_length_m * c.anomaly_length_m;
  for_each_epoch(c.rate_hz, d.route.duration(), [&](double t) {
    const KinematicState st = d.route.state_at(t);
    Eigen::Vector3d dist = Eigen::Vector3d::Zero();
    for (const auto& an : anomalies) dist += an.amplitude * std::exp(-(st.position.head<2>() - an.at).squaredNorm() / two_l2);
    const Eigen::Vector3d b = earth + dist;
    // ENU -> FLU for a level vehicle is a rotation by -yaw about z.
    const double cy = std::cos(st.yaw), sy = std::sin(st.yaw);
    MagSample m;
    m.t = t;
    m.field_ut = Eigen::Vector3d(cy * b.x() + sy * b.y(), -sy * b.x() + cy * b.y(), b.z());
    for (int i = 0; i < 3; ++i) m.field_ut[i] += c.noise_ut * rng.normal();
    m.disturbance_ut = dist.norm();
    d.mag.push_back(m);
  });
}

}  // namespace detail

/// Simulates the whole drive. Throws std::invalid_argument naming the offending field for a
/// configuration outside its documented range.
inline Drive simulate_drive(const DriveConfig& config) {
  detail::check_config(config);
  Drive d;
  d.config = config;
  d.route = make_route(config.route);
  detail::for_each_epoch(config.imu.rate_hz, d.route.duration(),
                         [&](double t) { d.truth.push_back(detail::make_truth(d.route, d.route.state_at(t))); });
  detail::simulate_imu(d);
  detail::simulate_gnss(d);
  detail::simulate_uwb(d);
  detail::simulate_speed(d);
  detail::simulate_magnetometer(d);
  return d;
}

}  // namespace ctxfuse::sim

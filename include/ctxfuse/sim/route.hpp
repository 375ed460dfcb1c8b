// The vehicle's true motion: a planar path whose curvature is continuous (linear ramps
// between straights and arcs) travelled with a speed profile whose acceleration is continuous
// (raised-cosine speed changes). Both are analytic, so the true state, angular rate and
// specific force can be evaluated at any time, and an IMU sampled from them integrates back
// to the same trajectory.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "ctxfuse/sim/config.hpp"
#include "ctxfuse/sim/world.hpp"

namespace ctxfuse::sim {

inline constexpr double kGravity = 9.80665;  // m/s^2, standard gravity (flat-site model)

/// One piece of the path over which curvature varies linearly from k0 to k1.
struct PathPiece {
  double s0 = 0.0, length = 0.0;
  double k0 = 0.0, k1 = 0.0;  // 1/m, positive turns left (counter-clockwise)
  Eigen::Vector2d start = Eigen::Vector2d::Zero();
  double yaw0 = 0.0;

  double curvature(double ds) const { return k0 + (k1 - k0) * ds / length; }
  double yaw(double ds) const { return yaw0 + k0 * ds + 0.5 * (k1 - k0) * ds * ds / length; }
  Eigen::Vector2d position(double ds) const {
    if (k0 == 0.0 && k1 == 0.0) return start + ds * Eigen::Vector2d(std::cos(yaw0), std::sin(yaw0));
    if (k0 == k1) {  // circular arc, closed form
      const double y1 = yaw0 + k0 * ds;
      return start + Eigen::Vector2d(std::sin(y1) - std::sin(yaw0), std::cos(yaw0) - std::cos(y1)) / k0;
    }
    // Clothoid: Gauss-Legendre (3 points) on sub-intervals of at most 0.5 m; the error is
    // far below a micrometre for the curvatures used here.
    const int n = std::max(1, static_cast<int>(std::ceil(ds / 0.5)));
    const double h = ds / n;
    static constexpr std::array<double, 3> node{-0.7745966692414834, 0.0, 0.7745966692414834};
    static constexpr std::array<double, 3> weight{5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
    Eigen::Vector2d p = start;
    for (int i = 0; i < n; ++i) {
      const double mid = (i + 0.5) * h;
      for (int j = 0; j < 3; ++j) {
        const double y = yaw(mid + 0.5 * h * node[static_cast<std::size_t>(j)]);
        p += 0.5 * h * weight[static_cast<std::size_t>(j)] * Eigen::Vector2d(std::cos(y), std::sin(y));
      }
    }
    return p;
  }
};

/// Builds a path from straights and constant-radius turns, then replaces every curvature
/// step with a linear ramp that borrows half its length from each neighbour, which keeps
/// every turn's total heading change exact.
class PathBuilder {
 public:
  PathBuilder(Eigen::Vector2d start, double yaw) : start_(start), yaw_(yaw) {}
  PathBuilder& straight(double length) { return add(length, 0.0); }
  /// angle > 0 turns left.
  PathBuilder& turn(double angle_rad, double radius) {
    return add(std::abs(angle_rad) * radius, (angle_rad > 0 ? 1.0 : -1.0) / radius);
  }
  double length() const {
    double s = 0.0;
    for (const auto& d : design_) s += d.length;
    return s;
  }

  std::vector<PathPiece> build(double ramp) const {
    std::vector<PathPiece> pieces;
    double s = 0.0;
    Eigen::Vector2d p = start_;
    double yaw = yaw_;
    auto push = [&](double len, double k0, double k1) {
      if (len <= 0.0) return;
      PathPiece piece{s, len, k0, k1, p, yaw};
      p = piece.position(len);
      yaw = piece.yaw(len);
      s += len;
      pieces.push_back(piece);
    };
    for (std::size_t i = 0; i < design_.size(); ++i) {
      const auto& d = design_[i];
      const bool ramp_in = i > 0 && design_[i - 1].curvature != d.curvature;
      const bool ramp_out = i + 1 < design_.size() && design_[i + 1].curvature != d.curvature;
      const double body = d.length - (ramp_in ? ramp / 2 : 0.0) - (ramp_out ? ramp / 2 : 0.0);
      if (body < 0.0)
        throw std::invalid_argument("sim route: segment " + std::to_string(i) + " of length " +
                                    std::to_string(d.length) + " m is shorter than the curvature ramps");
      push(body, d.curvature, d.curvature);
      if (ramp_out) push(ramp, d.curvature, design_[i + 1].curvature);
    }
    return pieces;
  }

 private:
  struct Design {
    double length;
    double curvature;
  };
  PathBuilder& add(double length, double curvature) {
    design_.push_back({length, curvature});
    return *this;
  }
  Eigen::Vector2d start_;
  double yaw_;
  std::vector<Design> design_;
};

/// A stretch of the path driven at one cruise speed, optionally ending in a stop.
struct SpeedLeg {
  double s_end = 0.0;
  double cruise_mps = 0.0;
  double stop_s = 0.0;  // > 0: come to rest at s_end and stay this long
};

/// Part of the speed profile: speed moves from v0 to v1 along a raised cosine (v0 == v1:
/// constant speed, including rest).
struct SpeedPhase {
  double t0 = 0.0, duration = 0.0, s0 = 0.0, v0 = 0.0, v1 = 0.0;

  double speed(double tau) const {
    if (v0 == v1) return v0;
    return v0 + (v1 - v0) * 0.5 * (1.0 - std::cos(std::numbers::pi * tau / duration));
  }
  double accel(double tau) const {
    if (v0 == v1) return 0.0;
    return (v1 - v0) * 0.5 * std::numbers::pi / duration * std::sin(std::numbers::pi * tau / duration);
  }
  double distance(double tau) const {
    if (v0 == v1) return v0 * tau;
    return v0 * tau + 0.5 * (v1 - v0) * (tau - duration / std::numbers::pi * std::sin(std::numbers::pi * tau / duration));
  }
};

/// Builds the phases for a sequence of legs starting at rest after `initial_rest_s`.
inline std::vector<SpeedPhase> plan_speed(const std::vector<SpeedLeg>& legs, double initial_rest_s, double max_accel) {
  std::vector<SpeedPhase> phases;
  double t = 0.0, s = 0.0, v = 0.0;
  auto add = [&](double duration, double v0, double v1) {
    if (duration <= 0.0) return;
    SpeedPhase ph{t, duration, s, v0, v1};
    s += ph.distance(duration);
    t += duration;
    phases.push_back(ph);
  };
  auto change_time = [&](double v0, double v1) { return std::numbers::pi * std::abs(v1 - v0) / (2.0 * max_accel); };
  add(initial_rest_s, 0.0, 0.0);
  for (std::size_t i = 0; i < legs.size(); ++i) {
    const auto& leg = legs[i];
    const double length = leg.s_end - s;
    const double v_out = leg.stop_s > 0.0 || i + 1 == legs.size() ? 0.0 : std::min(leg.cruise_mps, legs[i + 1].cruise_mps);
    // Lower the cruise speed until speeding up and slowing down fit into the leg.
    double cruise = leg.cruise_mps;
    auto needed = [&](double c) {
      return 0.5 * (v + c) * change_time(v, c) + 0.5 * (c + v_out) * change_time(c, v_out);
    };
    if (needed(std::max(v, v_out)) > length + 1e-9)
      throw std::invalid_argument("sim route: leg " + std::to_string(i) + " (" + std::to_string(length) +
                                  " m) is too short to change speed from " + std::to_string(v) + " to " +
                                  std::to_string(v_out) + " m/s");
    if (needed(cruise) > length) {
      double lo = std::max(v, v_out), hi = cruise;
      for (int it = 0; it < 60; ++it) (needed(0.5 * (lo + hi)) > length ? hi : lo) = 0.5 * (lo + hi);
      cruise = lo;
    }
    add(change_time(v, cruise), v, cruise);
    const double cruise_len = length - needed(cruise);
    if (cruise > 0.0) add(cruise_len / cruise, cruise, cruise);
    add(change_time(cruise, v_out), cruise, v_out);
    s = leg.s_end;  // remove rounding drift so the next leg starts exactly at its mark
    v = v_out;
    if (v_out == 0.0) add(i + 1 == legs.size() ? leg.stop_s : leg.stop_s, 0.0, 0.0);
  }
  return phases;
}

/// The true kinematic state at one instant.
struct KinematicState {
  double t = 0.0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // ENU, m (z = 0: the vehicle's reference point on the ground)
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  // ENU, m/s
  double yaw = 0.0;                                    // rad, CCW from east, wrapped to (-pi, pi]
  double speed = 0.0;                                  // forward speed, m/s (never negative)
  double accel = 0.0;                                  // forward acceleration, m/s^2
  double curvature = 0.0;                              // 1/m
  Eigen::Vector3d angular_rate_body = Eigen::Vector3d::Zero();  // FLU, rad/s
  Eigen::Vector3d specific_force_body = Eigen::Vector3d::Zero();  // FLU, m/s^2 (gravity reaction included)
  bool is_static = false;
};

/// The route: path + speed profile + the world built around it.
struct Route {
  std::vector<PathPiece> path;
  std::vector<SpeedPhase> phases;
  World world;

  double duration() const { return phases.empty() ? 0.0 : phases.back().t0 + phases.back().duration; }
  double length() const { return path.empty() ? 0.0 : path.back().s0 + path.back().length; }

  KinematicState state_at(double t) const {
    auto it = std::upper_bound(phases.begin(), phases.end(), t, [](double v, const SpeedPhase& p) { return v < p.t0; });
    const SpeedPhase& ph = it == phases.begin() ? phases.front() : *std::prev(it);
    const double tau = std::clamp(t - ph.t0, 0.0, ph.duration);
    KinematicState st;
    st.t = t;
    st.speed = std::max(0.0, ph.speed(tau));
    st.accel = ph.accel(tau);
    const double s = std::clamp(ph.s0 + ph.distance(tau), 0.0, length());
    auto pit = std::upper_bound(path.begin(), path.end(), s, [](double v, const PathPiece& p) { return v < p.s0; });
    const PathPiece& piece = pit == path.begin() ? path.front() : *std::prev(pit);
    const double ds = std::min(s - piece.s0, piece.length);
    const Eigen::Vector2d p2 = piece.position(ds);
    const double yaw = piece.yaw(ds);
    st.yaw = std::remainder(yaw, 2.0 * std::numbers::pi);
    st.curvature = piece.curvature(ds);
    st.position = Eigen::Vector3d(p2.x(), p2.y(), 0.0);
    st.velocity = Eigen::Vector3d(std::cos(yaw), std::sin(yaw), 0.0) * st.speed;
    st.angular_rate_body = Eigen::Vector3d(0.0, 0.0, st.curvature * st.speed);
    st.specific_force_body = Eigen::Vector3d(st.accel, st.curvature * st.speed * st.speed, kGravity);
    st.is_static = ph.v0 == 0.0 && ph.v1 == 0.0;
    return st;
  }
};

/// Free lengths of the route, solved so that the region shares come out as configured.
struct RouteLayout {
  double outdoor_scale = 1.0;  // multiplies the outdoor street lengths
  double approach_length_m = 60.0;  // transition: covered approach, west of the entrance
  double garage_lap_east_m = 50.0;  // indoor: x of the east side of the lap inside the garage
};

namespace detail {

inline Route build_route(const RouteConfig& cfg, const RouteLayout& lay) {
  const double pi = std::numbers::pi;
  // Outdoor streets (nominal lengths, scaled) and turn radii.
  const double R = 20.0;
  const double o1 = 120.0 * lay.outdoor_scale, o2 = 160.0 * lay.outdoor_scale, o3 = 60.0 * lay.outdoor_scale;
  const double o4 = o3 + 2.0 * R + 80.0 * lay.outdoor_scale, o5 = 200.0 * lay.outdoor_scale;
  const double L = lay.approach_length_m;
  // Garage lap: rectangle x in [xw, xe], y in [-Y, Y], corner radius r.
  const double r = 5.0, xw = 12.0, Y = 16.0, xe = lay.garage_lap_east_m;
  const double vo = cfg.outdoor_speed_mps, vt = cfg.transition_speed_mps, vi = cfg.indoor_speed_mps;

  const Eigen::Vector2d start(-L - o3 - 2.0 * R - o1, -2.0 * R - o2);
  PathBuilder pb(start, 0.0);
  std::vector<SpeedLeg> legs;
  auto leg = [&](double v, double stop = 0.0) { legs.push_back({pb.length(), v, stop}); };
  // Outdoor 1: east, left into the obstructed street (north), right towards the approach (east).
  pb.straight(o1 * 0.5); leg(vo, cfg.traffic_stop_s);
  pb.straight(o1 * 0.5).turn(pi / 2, R).straight(o2).turn(-pi / 2, R).straight(o3); leg(vo);
  // Transition in: covered approach with a barrier gate half way.
  pb.straight(L * 0.5); leg(vt, cfg.gate_stop_s);
  pb.straight(L * 0.5); leg(vt);
  // Indoor: along the entry lane, then laps around the pillars, parking stop on the first lap.
  pb.straight(xe - r).turn(pi / 2, r).straight(Y - 2 * r).turn(pi / 2, r);
  pb.straight((xe - xw - 2 * r) * 0.5); leg(vi, cfg.parking_stop_s);
  pb.straight((xe - xw - 2 * r) * 0.5).turn(pi / 2, r);
  for (int lap = 1; lap < cfg.indoor_laps; ++lap)
    pb.straight(2 * Y - 2 * r).turn(pi / 2, r).straight(xe - xw - 2 * r).turn(pi / 2, r)
        .straight(2 * Y - 2 * r).turn(pi / 2, r).straight(xe - xw - 2 * r).turn(pi / 2, r);
  pb.straight(Y - 2 * r).turn(-pi / 2, r).straight(xw - r); leg(vi);
  // Transition out, then outdoor 2: west, right (north) with a traffic stop, final rest.
  pb.straight(L); leg(vt);
  pb.straight(o4).turn(-pi / 2, R).straight(o5 * 0.5); leg(vo, cfg.traffic_stop_s);
  pb.straight(o5 * 0.5); leg(vo, cfg.final_static_s);

  Route route;
  route.path = pb.build(cfg.curvature_ramp_m);
  route.phases = plan_speed(legs, cfg.initial_static_s, cfg.max_accel_mps2);

  // World around the path.
  const double garage_east = xe + 8.0, garage_half = Y + 8.0, door_half = 5.0, approach_half = 6.0;
  World& w = route.world;
  w.indoor = Polygon::rectangle(0.0, -garage_half, garage_east, garage_half);
  w.transition = Polygon::rectangle(-L, -approach_half, 0.0, approach_half);
  // Approach: tall buildings 6 m either side of the lane plus a canopy.
  // The approach opens onto the street at its west end and closes towards the garage.
  w.canyons.push_back({w.transition, 0.0, 12.0, approach_half, 3.0, {-L, 0.0}, {0.0, 0.0},
                       std::min(cfg.approach_open_end_height_m, 12.0)});
  w.garage_door = {{0.0, -door_half}, {0.0, door_half}, cfg.garage_door_height_m};
  // The north-going street of the first outdoor part is a canyon (obstructed scene).
  const double xs = -L - o3 - R;
  w.canyons.push_back({Polygon::rectangle(xs - 12.0, -R - o2, xs + 12.0, -R), pi / 2, 14.0, 11.0, 0.0});
  // Garage walls with the doorway on the west side.
  auto wall = [&](double x0, double y0, double x1, double y1) { w.walls.push_back({{x0, y0}, {x1, y1}}); };
  wall(0.0, -garage_half, garage_east, -garage_half);
  wall(garage_east, -garage_half, garage_east, garage_half);
  wall(garage_east, garage_half, 0.0, garage_half);
  wall(0.0, garage_half, 0.0, door_half);
  wall(0.0, -door_half, 0.0, -garage_half);
  // Approach walls (building faces).
  wall(-L, approach_half, 0.0, approach_half);
  wall(-L, -approach_half, 0.0, -approach_half);
  // Pillars (0.8 m squares) in the island inside the lap.
  for (double x = xw + 8.0; x <= xe - 8.0; x += 10.0)
    for (double y : {-Y / 2.0, Y / 2.0}) {
      wall(x - 0.4, y - 0.4, x + 0.4, y - 0.4);
      wall(x + 0.4, y - 0.4, x + 0.4, y + 0.4);
      wall(x + 0.4, y + 0.4, x - 0.4, y + 0.4);
      wall(x - 0.4, y + 0.4, x - 0.4, y - 0.4);
    }
  // UWB anchors: four garage corners, one mid-garage on the east wall, two at the approach
  // (unless RouteConfig::approach_uwb_anchors is off).
  const double za = 2.8;
  w.anchors = {{0, {3.0, garage_half - 3.0, za}},  {1, {3.0, -garage_half + 3.0, za}},
               {2, {garage_east - 3.0, garage_half - 3.0, za}}, {3, {garage_east - 3.0, -garage_half + 3.0, za}},
               {4, {garage_east - 1.0, 0.0, za}}};
  if (cfg.approach_uwb_anchors) {
    w.anchors.push_back({5, {-8.0, approach_half - 1.0, 3.0}});
    w.anchors.push_back({6, {-8.0, -approach_half + 1.0, 3.0}});
  }
  return route;
}

/// Seconds spent in each region, sampling the route at 20 Hz (ample for a layout).
inline std::array<double, 3> region_times(const Route& route) {
  std::array<double, 3> t{};
  const double dt = 0.05;
  const auto n = static_cast<long>(route.duration() / dt);
  for (long k = 0; k < n; ++k) {
    const auto st = route.state_at((static_cast<double>(k) + 0.5) * dt);
    t[static_cast<std::size_t>(route.world.region_at(st.position))] += dt;
  }
  return t;
}

}  // namespace detail

/// Builds the route and solves its three free lengths (outdoor scale, approach length,
/// garage lap length) so that the time in each region matches duration * share. Throws
/// std::invalid_argument naming the offending field when the configuration cannot be met.
inline Route make_route(const RouteConfig& cfg) {
  auto bad = [](const std::string& what) { throw std::invalid_argument("sim RouteConfig: " + what); };
  if (!(cfg.duration_s >= 120.0 && cfg.duration_s <= 7200.0)) bad("duration_s must be within [120, 7200] s");
  double sum = 0.0;
  for (double s : cfg.region_shares) {
    if (!(s >= 0.05 && s <= 0.9)) bad("each of region_shares must be within [0.05, 0.9]");
    sum += s;
  }
  if (std::abs(sum - 1.0) > 1e-6) bad("region_shares must sum to 1");
  for (double v : {cfg.outdoor_speed_mps, cfg.transition_speed_mps, cfg.indoor_speed_mps})
    if (!(v >= 0.5 && v <= 30.0)) bad("speeds must be within [0.5, 30] m/s");
  if (!(cfg.max_accel_mps2 >= 0.2 && cfg.max_accel_mps2 <= 5.0)) bad("max_accel_mps2 must be within [0.2, 5]");
  if (!(cfg.approach_open_end_height_m >= 0.0 && cfg.approach_open_end_height_m <= 12.0))
    bad("approach_open_end_height_m must be within [0, 12] m");
  if (!(cfg.garage_door_height_m >= 0.0 && cfg.garage_door_height_m <= 10.0)) bad("garage_door_height_m must be within [0, 10] m");
  if (cfg.indoor_laps < 1 || cfg.indoor_laps > 50) bad("indoor_laps must be within [1, 50]");
  if (!(cfg.curvature_ramp_m >= 0.5 && cfg.curvature_ramp_m <= 8.0)) bad("curvature_ramp_m must be within [0.5, 8] m");
  for (double s : {cfg.initial_static_s, cfg.traffic_stop_s, cfg.gate_stop_s, cfg.parking_stop_s, cfg.final_static_s})
    if (!(s >= 0.0 && s <= 600.0)) bad("stop durations must be within [0, 600] s");

  RouteLayout lay;
  const std::array<double, 3> target{cfg.region_shares[0] * cfg.duration_s, cfg.region_shares[1] * cfg.duration_s,
                                     cfg.region_shares[2] * cfg.duration_s};
  // Each free length moves (almost only) its own region's time, linearly while the legs have
  // a cruise phase: a few secant steps per length suffice.
  auto get = [&](RouteLayout& l, int i) -> double& {
    return i == 0 ? l.outdoor_scale : i == 1 ? l.approach_length_m : l.garage_lap_east_m;
  };
  const std::array<double, 3> lower{0.3, 20.0, 35.0};
  const std::array<double, 3> step{0.1, 10.0, 5.0};
  for (int iter = 0; iter < 6; ++iter) {
    const auto t0 = detail::region_times(detail::build_route(cfg, lay));
    bool done = true;
    for (int i = 0; i < 3; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      if (std::abs(t0[ii] - target[ii]) < 0.05) continue;
      done = false;
      RouteLayout probe = lay;
      get(probe, i) += step[ii];
      const auto t1 = detail::region_times(detail::build_route(cfg, probe));
      const double slope = (t1[ii] - t0[ii]) / step[ii];
      if (slope > 0.0) get(lay, i) = std::max(lower[ii], get(lay, i) + (target[ii] - t0[ii]) / slope);
    }
    if (done) break;
  }
  return detail::build_route(cfg, lay);
}

}  // namespace ctxfuse::sim

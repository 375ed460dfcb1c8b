// A simulated UWB site in the Hanyang layout: given the tag's true path (time-stamped 3-D
// positions of its antenna), fixed anchors, each ranging at its own rate, reports raw or the
// mean of the last n raw ranges, per-anchor constant biases, Gaussian noise and optionally an
// NLOS excess, `simulate_uwb_site` makes the messages::UwbRange streams; io::write_hanyang_case
// (io/hanyang_uwb.hpp) writes them and `hanyang_reference` in the dataset's files, so that
// `ctxfuse run uwb` reads a simulated case exactly as a recorded one.
//
// Each anchor's reports fall at t0 + phase + k / rate (plus Gaussian jitter of rate_jitter_s,
// kept inside the slot's half period so that the order of one anchor's reports stays), for
// every slot inside the path's time span. A raw range is |p(t) - anchor| + bias + noise (+ an
// NLOS excess: exponential with mean nlos.mean_excess_m, with probability nlos.probability per
// raw range); a report is the mean of the last `average_samples` raw ranges of its anchor (of
// the ones there are at the start). Powers: rssi_dbm, and a first-path power lower by
// nlos.first_path_drop_db on an NLOS range (rssi - rssi_fp grows under NLOS, as on the DW1000).
// The path is interpolated linearly between its samples. One seeded stream (sim/random.hpp,
// Stream::uwb): the same seed and configuration give the same ranges.
//
// `pedestrian_walk` is a path for tests and `ctxfuse sim`: a static start, then walking at a
// constant speed between random waypoints inside a rectangle, turning at a bounded rate.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "ctxfuse/io/hanyang_uwb.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/sim/random.hpp"

namespace ctxfuse::sim {

/// The tag antenna's true position at time t [s].
struct PositionSample {
  double t = 0.0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

struct SiteAnchor {
  int id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double rate_hz = 10.0;  // reports per second
  double phase_s = 0.0;   // first report after the path's start
  double bias_m = 0.0;    // constant range bias (antenna delay left over from calibration)
};

struct NlosExcess {
  double probability = 0.0;     // per raw range
  double mean_excess_m = 0.0;   // exponential excess
  double first_path_drop_db = 6.0;
};

struct UwbSiteConfig {
  std::vector<SiteAnchor> anchors;
  double noise_sigma_m = 0.10;  // per raw range
  int average_samples = 1;      // 1: raw reports
  double rate_jitter_s = 0.0;   // 1-sigma of a report's stamp around its slot
  NlosExcess nlos;
  double rssi_dbm = -80.0;
  std::uint64_t seed = 1;
};

/// The path's position at t (linear interpolation; held outside the path's span).
inline Eigen::Vector3d position_at(std::span<const PositionSample> path, double t) {
  if (t <= path.front().t) return path.front().position;
  if (t >= path.back().t) return path.back().position;
  const auto it = std::lower_bound(path.begin(), path.end(), t, [](const PositionSample& p, double v) { return p.t < v; });
  const auto& b = *it;
  const auto& a = *(it - 1);
  const double w = (t - a.t) / (b.t - a.t);
  return (1.0 - w) * a.position + w * b.position;
}

/// The ranges of every anchor, merged in time order (then anchor id). Throws
/// std::invalid_argument for a path with fewer than two samples or times that do not
/// increase, an anchor rate outside (0, 1000] Hz, a negative phase, a non-finite value, a
/// noise sigma or jitter below 0, average_samples outside 1..100, or two anchors with one id.
inline std::vector<messages::UwbRange> simulate_uwb_site(std::span<const PositionSample> path, const UwbSiteConfig& c) {
  if (path.size() < 2) throw std::invalid_argument("simulate_uwb_site: the path needs two samples");
  for (std::size_t i = 0; i < path.size(); ++i)
    if (!std::isfinite(path[i].t) || !path[i].position.allFinite() || (i > 0 && !(path[i].t > path[i - 1].t)))
      throw std::invalid_argument("simulate_uwb_site: path sample " + std::to_string(i) + " not finite or not after the previous");
  if (!(c.noise_sigma_m >= 0.0 && std::isfinite(c.noise_sigma_m)) || !(c.rate_jitter_s >= 0.0 && std::isfinite(c.rate_jitter_s)))
    throw std::invalid_argument("simulate_uwb_site: noise sigma and jitter must be finite and >= 0");
  if (c.average_samples < 1 || c.average_samples > 100) throw std::invalid_argument("simulate_uwb_site: average_samples outside 1..100");
  if (!(c.nlos.probability >= 0.0 && c.nlos.probability <= 1.0 && c.nlos.mean_excess_m >= 0.0 && std::isfinite(c.nlos.mean_excess_m)))
    throw std::invalid_argument("simulate_uwb_site: NLOS probability outside [0, 1] or excess not finite and >= 0");
  for (std::size_t a = 0; a < c.anchors.size(); ++a) {
    const SiteAnchor& an = c.anchors[a];
    if (!(an.rate_hz > 0.0 && an.rate_hz <= 1000.0) || !(an.phase_s >= 0.0 && std::isfinite(an.phase_s)) || !an.position.allFinite() ||
        !std::isfinite(an.bias_m))
      throw std::invalid_argument("simulate_uwb_site: anchor " + std::to_string(an.id) + ": rate outside (0, 1000] Hz or a value not finite");
    for (std::size_t b = 0; b < a; ++b)
      if (c.anchors[b].id == an.id) throw std::invalid_argument("simulate_uwb_site: anchor id " + std::to_string(an.id) + " twice");
  }
  Rng rng(c.seed, Stream::uwb);
  std::vector<messages::UwbRange> out;
  const double t0 = path.front().t, t1 = path.back().t;
  std::vector<double> raw;
  for (const SiteAnchor& an : c.anchors) {
    const double period = 1.0 / an.rate_hz;
    const double jitter_bound = 0.45 * period;
    raw.clear();
    for (long k = 0;; ++k) {
      const double slot = t0 + an.phase_s + static_cast<double>(k) * period;
      if (slot > t1) break;
      const double t = std::clamp(slot + std::clamp(rng.normal(0.0, c.rate_jitter_s), -jitter_bound, jitter_bound), t0, t1);
      const bool nlos = c.nlos.probability > 0.0 && rng.bernoulli(c.nlos.probability);
      double r = (position_at(path, t) - an.position).norm() + an.bias_m + rng.normal(0.0, c.noise_sigma_m);
      if (nlos) r += -c.nlos.mean_excess_m * std::log(rng.uniform());
      raw.push_back(r);
      const std::size_t n = std::min(raw.size(), static_cast<std::size_t>(c.average_samples));
      double mean = 0.0;
      for (std::size_t i = raw.size() - n; i < raw.size(); ++i) mean += raw[i];
      messages::UwbRange u;
      u.t = t;
      u.anchor_id = an.id;
      u.anchor_position = an.position;
      u.range_m = std::max(0.0, mean / static_cast<double>(n));
      u.rssi_dbm = c.rssi_dbm;
      u.rssi_first_path_dbm = c.rssi_dbm - 1.0 - (nlos ? c.nlos.first_path_drop_db : 0.0);
      out.push_back(u);
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const messages::UwbRange& a, const messages::UwbRange& b) {
    return a.t != b.t ? a.t < b.t : a.anchor_id < b.anchor_id;
  });
  return out;
}

/// The Hanyang reference of a path: the reference point `tag_height_m` below the antenna (the
/// authors' protocol compares the estimate's z with reference z + tag height), heading from the
/// direction of travel [deg, unwrapped; held while the path does not move].
inline std::vector<io::HanyangReferencePose> hanyang_reference(std::span<const PositionSample> path, double tag_height_m) {
  std::vector<io::HanyangReferencePose> out;
  out.reserve(path.size());
  double heading = 0.0;
  for (std::size_t i = 0; i < path.size(); ++i) {
    io::HanyangReferencePose p;
    p.t = path[i].t;
    p.position = path[i].position - Eigen::Vector3d(0.0, 0.0, tag_height_m);
    if (i + 1 < path.size()) {
      const Eigen::Vector2d d = (path[i + 1].position - path[i].position).head<2>();
      if (d.norm() > 1e-9) {
        const double h = std::atan2(d.y(), d.x()) * 180.0 / std::numbers::pi;
        heading += std::remainder(h - heading, 360.0);
      }
    }
    p.heading_deg = heading;
    out.push_back(p);
  }
  return out;
}

struct WalkConfig {
  Eigen::Vector2d min_corner = Eigen::Vector2d::Zero(), max_corner = Eigen::Vector2d(20.0, 20.0);
  double margin_m = 2.0;          // waypoints stay this far inside the rectangle
  double static_s = 10.0;         // at rest at the start
  double walk_s = 120.0;
  double speed_mps = 1.2;
  double max_turn_rate_dps = 90.0;
  double tag_height_m = 1.0;
  double dt_s = 0.01;
  std::uint64_t seed = 1;
  double t0 = 0.0;
};

/// A pedestrian-like path: at rest at the rectangle's centre for static_s, then walking at
/// speed_mps towards random waypoints (uniform inside the rectangle less the margin; a new one
/// when within 1 m of the current), the heading turning towards it at most max_turn_rate_dps.
inline std::vector<PositionSample> pedestrian_walk(const WalkConfig& w) {
  Rng rng(w.seed, Stream::uwb);
  const Eigen::Vector2d lo = w.min_corner.array() + w.margin_m, hi = w.max_corner.array() - w.margin_m;
  if (!(lo.array() < hi.array()).all() || !(w.dt_s > 0.0) || !(w.speed_mps >= 0.0) || !(w.static_s >= 0.0) || !(w.walk_s >= 0.0))
    throw std::invalid_argument("pedestrian_walk: empty rectangle, or dt, speed or durations not positive");
  auto waypoint = [&] { return Eigen::Vector2d(rng.uniform(lo.x(), hi.x()), rng.uniform(lo.y(), hi.y())); };
  Eigen::Vector2d p = 0.5 * (w.min_corner + w.max_corner), target = waypoint();
  double heading = std::atan2(target.y() - p.y(), target.x() - p.x());
  std::vector<PositionSample> out;
  const long steps = std::lround((w.static_s + w.walk_s) / w.dt_s);
  const double max_turn = w.max_turn_rate_dps * std::numbers::pi / 180.0 * w.dt_s;
  for (long k = 0; k <= steps; ++k) {
    const double t = static_cast<double>(k) * w.dt_s;
    out.push_back({w.t0 + t, Eigen::Vector3d(p.x(), p.y(), w.tag_height_m)});
    if (t < w.static_s) continue;
    if ((target - p).norm() < 1.0) target = waypoint();
    const double want = std::atan2(target.y() - p.y(), target.x() - p.x());
    heading += std::clamp(std::remainder(want - heading, 2.0 * std::numbers::pi), -max_turn, max_turn);
    p += w.speed_mps * w.dt_s * Eigen::Vector2d(std::cos(heading), std::sin(heading));
    p = p.cwiseMax(w.min_corner).cwiseMin(w.max_corner);
  }
  return out;
}

}  // namespace ctxfuse::sim

// The plots of `ctxfuse run gins --plot DIR` (gnuplot through cli/plot.hpp; each PNG with its
// .dat and .gp). The reference is the recording's RTK-fixed epochs (studies/outage_protocol.hpp),
// the same ones the JSON's outage scores use; the pipeline never sees them.
//   gins_trajectory   plan view, east/north [m] from the first reference epoch: the forward
//                     (and smoothed) trajectory, the reference, the reference inside outages;
//   gins_error_time   horizontal error at every reference epoch against time since the first
//                     fix, the epochs inside outages on their own, and the filter's 1-sigma
//                     horizontal (sqrt(sd_n^2 + sd_e^2) of the trajectory, interpolated);
//   gins_outage_error RMS and max of the horizontal error per outage window with a scored epoch
//                     (the JSON's per-outage figures), against the window's number (1 = first).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "cli/plot.hpp"
#include "ctxfuse/studies/gins_outages.hpp"

namespace ctxfuse::cli {

/// East/north [m] from an origin with the origin's radii: a plan view over a few km.
struct LocalPlane {
  double lat0 = 0.0, lon0 = 0.0;  // [rad]
  Eigen::Vector3d per = earth::ned_per_llh(0.0, 0.0);
  LocalPlane(double lat, double lon) : lat0(lat), lon0(lon), per(earth::ned_per_llh(lat, 0.0)) {}
  Eigen::Vector2d operator()(double lat, double lon) const {
    return {std::remainder(lon - lon0, 2.0 * 3.14159265358979323846) * per(1), (lat - lat0) * per(0)};
  }
};

/// 1-sigma horizontal [m] of the trajectory at t, interpolated between its rows.
inline double sigma_horizontal_at(std::span<const pipelines::gins::TrajectoryRow> rows, double t) {
  const auto it = std::lower_bound(rows.begin(), rows.end(), t, [](const auto& r, double x) { return r.t < x; });
  if (it == rows.end()) return std::nan("");
  auto h = [](const pipelines::gins::TrajectoryRow& r) { return std::hypot(r.sd_position(0), r.sd_position(1)); };
  if (it == rows.begin() || it->t == t) return h(*it);
  const auto& a = *(it - 1);
  const double w = (t - a.t) / (it->t - a.t);
  return (1.0 - w) * h(a) + w * h(*it);
}

inline void plot_gins(Plotter& plotter, std::span<const messages::GnssFix> fixes, const pipelines::gins::RunResult& res,
                      const ctxfuse::studies::GinsOutageScores& scores) {
  using Series = Plotter::Series;
  const auto ref = ctxfuse::studies::rtk_fixed_reference(fixes);
  if (ref.empty() || res.forward.empty()) return;
  const double t0 = fixes.front().t;
  const LocalPlane plane(ref.front().lat, ref.front().lon);
  auto in_outage = [&](double t) {
    return std::any_of(res.windows.begin(), res.windows.end(), [&](const auto& w) { return w.contains(t); });
  };
  struct Pass {
    const char* name;
    const std::vector<pipelines::gins::TrajectoryRow>* rows;
    const ctxfuse::studies::OutageErrors* scores;
  };
  std::vector<Pass> passes{{"forward", &res.forward, &scores.forward}};
  if (!res.smoothed.empty()) passes.push_back({"smoothed", &res.smoothed, &scores.smoothed});

  std::vector<Series> traj{{"RTK reference (Q=1)", {}, false}, {"reference inside outages", {}, false}};
  for (const auto& r : ref) traj[in_outage(r.t) ? 1 : 0].points.push_back(plane(r.lat, r.lon));
  for (const auto& p : passes) {
    Series s{p.name, {}, true};
    double last = -std::numeric_limits<double>::infinity();
    for (const auto& row : *p.rows)
      if (row.t - last >= 0.1) {  // 10 Hz is plenty for a plan view
        s.points.push_back(plane(row.llh(0), row.llh(1)));
        last = row.t;
      }
    traj.push_back(std::move(s));
  }
  plotter.trajectory("gins_trajectory", "GNSS/INS against the RTK-fixed reference, outages marked (east/north from the first fixed epoch)",
                     traj);

  std::vector<Series> err, per_outage;
  for (const auto& p : passes) {
    const auto ll = ctxfuse::studies::lat_lon_of(*p.rows);
    Series all{std::string(p.name) + " horizontal error", {}, true}, inside{std::string(p.name) + " error inside outages", {}, false},
        sigma{std::string(p.name) + " 1-sigma horizontal", {}, true};
    for (const auto& r : ref) {
      // The error the outage scores aggregate (ctxfuse::studies::horizontal_error_at).
      const std::optional<double> err = ctxfuse::studies::horizontal_error_at(ll, r);
      if (!err) continue;
      const double e = *err;
      all.points.emplace_back(r.t - t0, e);
      if (in_outage(r.t)) inside.points.emplace_back(r.t - t0, e);
      sigma.points.emplace_back(r.t - t0, sigma_horizontal_at(*p.rows, r.t));
    }
    err.push_back(std::move(all));
    err.push_back(std::move(inside));
    err.push_back(std::move(sigma));
    Series rms{std::string(p.name) + " RMS", {}, false}, max{std::string(p.name) + " max", {}, false};
    for (std::size_t i = 0; i < p.scores->outages.size(); ++i)
      if (const auto& o = p.scores->outages[i]; o.epochs > 0) {
        rms.points.emplace_back(static_cast<double>(i + 1), o.rms);
        max.points.emplace_back(static_cast<double>(i + 1), o.max);
      }
    per_outage.push_back(std::move(rms));
    per_outage.push_back(std::move(max));
  }
  plotter.xy("gins_error_time", "Horizontal error at the RTK-fixed epochs and the filter's 1-sigma", "time since the first fix [s]",
             "horizontal [m]", err, "set logscale y\nset key bottom right\n");
  if (!res.windows.empty())
    plotter.xy("gins_outage_error", "Horizontal error per GNSS outage (RTK-fixed epochs inside the window)", "outage (1 = first window)",
               "horizontal error [m]", per_outage, "set offsets 0.5, 0.5, 0, 0\nset xtics 1\nset yrange [0:*]\n");
}

}  // namespace ctxfuse::cli

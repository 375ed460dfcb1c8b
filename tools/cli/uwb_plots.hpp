// The plots of the NLOS-robust UWB pipeline (`ctxfuse run uwb --plot DIR` on a Hanyang case,
// and the demo's nlos_uwb section on the simulated drive), through cli/plot.hpp:
//   PREFIX_trajectory  plan view [m]: the reference, the estimates of the epochs with a range
//                      attached, the estimates of the left-out epochs (every range left out by
//                      the NLOS policy or none in the epoch) on their own, the anchors;
//   PREFIX_error_time  2-D error of the scored estimates against time, the left-out ones marked;
//   PREFIX_error_cdf   empirical CDF of the 2-D error: the plotted estimator first, then others.
// The caller supplies the errors from its own scoring (the truth side stays in eval/ or the tool).
#pragma once

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "cli/plot.hpp"

namespace ctxfuse::cli {

struct UwbPlotEstimate {
  double t = 0.0;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  bool attached = false;     // false: a left-out epoch
  double error = std::nan(""); // 2-D error [m]; NaN: not scored (outside the scored span)
};

struct UwbPlots {
  std::string prefix;     // file names PREFIX_trajectory, PREFIX_error_time, PREFIX_error_cdf
  std::string estimator;  // its label in the plots
  std::string reference_label = "reference";
  std::vector<Eigen::Vector2d> reference, anchors;
  std::vector<UwbPlotEstimate> estimates;
  double t0 = 0.0;  // time origin of the error plot
  std::string time_label = "time [s]";
  std::vector<std::pair<std::string, std::vector<double>>> other_errors;  // CDFs beside the estimator's
};

inline void plot_uwb(Plotter& plotter, const UwbPlots& in) {
  using Series = Plotter::Series;
  Series attached{in.estimator + ", epochs with ranges attached", {}, false}, left{in.estimator + ", left-out epochs", {}, false};
  Series err{in.estimator + " 2-D error", {}, true}, err_left{"left-out epochs", {}, false};
  std::vector<double> errors;
  for (const auto& e : in.estimates) {
    (e.attached ? attached : left).points.push_back(e.position);
    if (std::isnan(e.error)) continue;
    err.points.emplace_back(e.t - in.t0, e.error);
    if (!e.attached) err_left.points.emplace_back(e.t - in.t0, e.error);
    errors.push_back(e.error);
  }
  plotter.trajectory(in.prefix + "_trajectory", in.estimator + " against the " + in.reference_label + ", left-out epochs and anchors",
                     {{in.reference_label, in.reference, true}, attached, left, {"UWB anchors", in.anchors, false}});
  plotter.xy(in.prefix + "_error_time", in.estimator + ": 2-D error against the " + in.reference_label + ", left-out epochs marked",
             in.time_label, "2-D error [m]", {err, err_left});
  std::vector<std::pair<std::string, std::vector<double>>> cdf{{in.estimator, std::move(errors)}};
  cdf.insert(cdf.end(), in.other_errors.begin(), in.other_errors.end());
  plotter.error_cdf(in.prefix + "_error_cdf", "2-D error CDF against the " + in.reference_label, cdf);
}

}  // namespace ctxfuse::cli

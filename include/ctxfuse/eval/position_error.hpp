// Position error statistics as the papers report them: mean, RMSE (per axis and horizontal),
// MAX, STD and error-CDF percentiles, overall and per label (e.g. per region).
//
// Definitions (n samples, e_i the scalar error of sample i):
//  - mean = sum e_i / n;  rmse = sqrt(sum e_i^2 / n);  max = max e_i;
//  - std  = sqrt(sum (e_i - mean)^2 / n)  (population form, so that rmse^2 = mean^2 + std^2);
//  - percentile p (0..100): linear interpolation between order statistics, the "type 7"
//    definition of Hyndman & Fan (1996), numpy's and R's default: with x sorted ascending,
//    h = (n - 1) p / 100, q = x[floor h] + (h - floor h) (x[floor h + 1] - x[floor h]).
//    So the 50 % value of {1, 2, 3, 4} is 2.5 and the 90 % value is 3.7.
// Horizontal error is sqrt(east^2 + north^2); per-axis statistics use the signed axis error
// for mean and rmse and |axis error| for percentiles (the "error CDF east/north" of paper C).
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace ctxfuse::eval {

inline constexpr std::array<double, 6> kPercentileLevels{50.0, 67.0, 70.0, 75.0, 90.0, 95.0};

/// Type-7 percentile of `values` (any order), p in [0, 100]. NaN for an empty input.
inline double percentile(std::vector<double> values, double p) {
  if (!(p >= 0.0 && p <= 100.0)) throw std::invalid_argument("percentile: p must be within [0, 100], got " + std::to_string(p));
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  const double h = (static_cast<double>(values.size()) - 1.0) * p / 100.0;
  const auto lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (h - static_cast<double>(lo)) * (values[hi] - values[lo]);
}

struct ScalarErrorStats {
  std::size_t count = 0;
  double mean = std::numeric_limits<double>::quiet_NaN();
  double rmse = std::numeric_limits<double>::quiet_NaN();
  double max = std::numeric_limits<double>::quiet_NaN();
  double std = std::numeric_limits<double>::quiet_NaN();
  std::array<double, kPercentileLevels.size()> percentiles;  // at kPercentileLevels

  ScalarErrorStats() { percentiles.fill(std::numeric_limits<double>::quiet_NaN()); }
  /// Percentile at one of kPercentileLevels (e.g. 67); throws for other levels.
  double at(double level) const {
    for (std::size_t i = 0; i < kPercentileLevels.size(); ++i)
      if (kPercentileLevels[i] == level) return percentiles[i];
    throw std::invalid_argument("ScalarErrorStats::at: " + std::to_string(level) + " % is not one of the computed levels");
  }
};

/// Statistics of a scalar error series. Throws std::invalid_argument naming the index of a
/// non-finite value.
inline ScalarErrorStats summarize(std::span<const double> e) {
  ScalarErrorStats s;
  s.count = e.size();
  if (e.empty()) return s;
  double sum = 0.0, sq = 0.0, mx = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < e.size(); ++i) {
    if (!std::isfinite(e[i])) throw std::invalid_argument("summarize: error sample " + std::to_string(i) + " is not finite");
    sum += e[i];
    sq += e[i] * e[i];
    mx = std::max(mx, e[i]);
  }
  const double n = static_cast<double>(e.size());
  s.mean = sum / n;
  s.rmse = std::sqrt(sq / n);
  s.max = mx;
  double var = 0.0;
  for (double x : e) var += (x - s.mean) * (x - s.mean);
  s.std = std::sqrt(var / n);
  std::vector<double> sorted(e.begin(), e.end());
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < kPercentileLevels.size(); ++i) s.percentiles[i] = percentile(sorted, kPercentileLevels[i]);
  return s;
}

struct PositionErrorStats {
  std::size_t count = 0;
  Eigen::Vector3d mean_axis = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());  // signed mean per axis (E, N, U)
  Eigen::Vector3d rmse_axis = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  ScalarErrorStats horizontal;  // of sqrt(e^2 + n^2): "mean position error", RMSE, MAX, STD, CDF
  ScalarErrorStats east_abs;    // of |e|: per-axis CDF
  ScalarErrorStats north_abs;   // of |n|
  ScalarErrorStats spatial;     // of the 3-D norm
};

/// Statistics of position errors (estimate - truth, ENU metres).
inline PositionErrorStats position_error_stats(std::span<const Eigen::Vector3d> errors) {
  PositionErrorStats s;
  s.count = errors.size();
  if (errors.empty()) return s;
  std::vector<double> h, ea, na, sp;
  h.reserve(errors.size());
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sq = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < errors.size(); ++i) {
    const auto& e = errors[i];
    if (!e.allFinite()) throw std::invalid_argument("position_error_stats: error sample " + std::to_string(i) + " is not finite");
    sum += e;
    sq += e.cwiseProduct(e);
    h.push_back(std::hypot(e.x(), e.y()));
    ea.push_back(std::abs(e.x()));
    na.push_back(std::abs(e.y()));
    sp.push_back(e.norm());
  }
  const double n = static_cast<double>(errors.size());
  s.mean_axis = sum / n;
  s.rmse_axis = (sq / n).cwiseSqrt();
  s.horizontal = summarize(h);
  s.east_abs = summarize(ea);
  s.north_abs = summarize(na);
  s.spatial = summarize(sp);
  return s;
}

/// Per-label breakdown: result[k] holds the samples whose label is k (0 <= k < num_labels).
/// Throws std::invalid_argument for mismatched lengths or a label out of range (naming it).
inline std::vector<PositionErrorStats> position_error_stats_by_label(std::span<const Eigen::Vector3d> errors,
                                                                     std::span<const int> labels, int num_labels) {
  if (errors.size() != labels.size())
    throw std::invalid_argument("position_error_stats_by_label: " + std::to_string(errors.size()) + " errors but " +
                                std::to_string(labels.size()) + " labels");
  if (num_labels < 1) throw std::invalid_argument("position_error_stats_by_label: num_labels must be >= 1");
  std::vector<std::vector<Eigen::Vector3d>> groups(static_cast<std::size_t>(num_labels));
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (labels[i] < 0 || labels[i] >= num_labels)
      throw std::invalid_argument("position_error_stats_by_label: label " + std::to_string(labels[i]) + " of sample " +
                                  std::to_string(i) + " is outside [0, " + std::to_string(num_labels - 1) + "]");
    groups[static_cast<std::size_t>(labels[i])].push_back(errors[i]);
  }
  std::vector<PositionErrorStats> out;
  for (const auto& g : groups) out.push_back(position_error_stats(g));
  return out;
}

}  // namespace ctxfuse::eval

// Scoring of a planar track per true region (the region paper's tables 3-6): the mean
// horizontal error per region and overall, X/Y RMSE, and, for estimators that do not always
// have a solution of their own (single sensors), the same over the epochs where they have one.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <vector>

#include "ctxfuse/eval/truth.hpp"

namespace ctxfuse::eval {

/// The truth at a track's epochs: horizontal position and region.
struct TrackTruth {
  std::vector<Eigen::Vector2d> position;
  std::vector<int> region;
};

inline TrackTruth truth_at(std::span<const double> t, std::span<const sim::TruthSample> truth) {
  TrackTruth out;
  out.position.reserve(t.size());
  out.region.reserve(t.size());
  for (double x : t) {
    out.position.push_back(position_at(truth, x).head<2>());
    out.region.push_back(region_at(truth, x));
  }
  return out;
}

/// `mean` scores every epoch, an estimator without a solution at the position it holds (what
/// its user is left with); `mean_with_solution` scores only the epochs where it has one, and
/// `with_solution` counts them, so that a single sensor's accuracy and its availability are
/// reported apart. Index 0-2: regions (outdoor, transition, indoor), 3: overall.
struct TrackErrors {
  std::array<double, 4> mean{};
  std::array<double, 4> rmse_x{};
  std::array<double, 4> rmse_y{};
  std::array<std::size_t, 4> count{};
  std::array<double, 4> mean_with_solution{};  // NaN where there is no such epoch
  std::array<std::size_t, 4> with_solution{};
  double availability(std::size_t k) const {
    return count[k] ? static_cast<double>(with_solution[k]) / static_cast<double>(count[k]) : 0.0;
  }
};

/// `solution` may be empty (every epoch has one).
inline TrackErrors region_errors(std::span<const Eigen::Vector2d> estimate, const std::vector<bool>& solution,
                                 const TrackTruth& truth) {
  TrackErrors out;
  std::array<double, 4> sum{}, sx{}, sy{}, sum_solution{};
  for (std::size_t i = 0; i < estimate.size() && i < truth.position.size(); ++i) {
    const Eigen::Vector2d e = estimate[i] - truth.position[i];
    const bool has = i < solution.size() ? solution[i] : true;
    for (int k : {truth.region[i], 3}) {
      const auto kk = static_cast<std::size_t>(k);
      sum[kk] += e.norm();
      sx[kk] += e.x() * e.x();
      sy[kk] += e.y() * e.y();
      ++out.count[kk];
      if (has) {
        sum_solution[kk] += e.norm();
        ++out.with_solution[kk];
      }
    }
  }
  for (std::size_t k = 0; k < 4; ++k) {
    const double n = std::max<double>(1.0, static_cast<double>(out.count[k]));
    out.mean[k] = sum[k] / n;
    out.rmse_x[k] = std::sqrt(sx[k] / n);
    out.rmse_y[k] = std::sqrt(sy[k] / n);
    out.mean_with_solution[k] = out.with_solution[k] ? sum_solution[k] / static_cast<double>(out.with_solution[k])
                                                     : std::numeric_limits<double>::quiet_NaN();
  }
  return out;
}

/// Any track with `t`, `estimate` (2-D) and `solution`, scored against the truth.
template <class Track>
TrackErrors region_errors(const Track& track, std::span<const sim::TruthSample> truth) {
  return region_errors(track.estimate, track.solution, truth_at(track.t, truth));
}

}  // namespace ctxfuse::eval

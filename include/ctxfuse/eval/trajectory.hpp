// Lining up an estimated trajectory with the simulator's truth: the truth position is
// interpolated linearly to each estimate's time, and the estimate takes the region and scene
// labels of the truth sample at or before it.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "ctxfuse/eval/position_error.hpp"
#include "ctxfuse/sim/drive.hpp"

namespace ctxfuse::eval {

struct TimedPosition {
  double t = 0.0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // ENU, m
};

struct AlignedErrors {
  std::vector<double> t;
  std::vector<Eigen::Vector3d> errors;  // estimate - truth, ENU m
  std::vector<int> region;              // sim::Region of the truth
  std::vector<int> scene;               // sim::Scene of the truth
  std::size_t skipped = 0;              // estimates outside the truth's time span
};

/// Throws std::invalid_argument when the truth is empty or not strictly increasing in time.
inline AlignedErrors align_to_truth(std::span<const TimedPosition> estimates, std::span<const sim::TruthSample> truth) {
  if (truth.empty()) throw std::invalid_argument("align_to_truth: the truth is empty");
  for (std::size_t i = 1; i < truth.size(); ++i)
    if (!(truth[i].t > truth[i - 1].t))
      throw std::invalid_argument("align_to_truth: truth time does not increase at sample " + std::to_string(i));
  AlignedErrors out;
  for (const auto& e : estimates) {
    if (!(e.t >= truth.front().t && e.t <= truth.back().t) || !e.position.allFinite()) {
      ++out.skipped;
      continue;
    }
    auto it = std::upper_bound(truth.begin(), truth.end(), e.t, [](double t, const sim::TruthSample& s) { return t < s.t; });
    const std::size_t hi = std::min<std::size_t>(static_cast<std::size_t>(it - truth.begin()), truth.size() - 1);
    const std::size_t lo = hi == 0 ? 0 : hi - 1;
    const auto& a = truth[e.t >= truth[hi].t ? hi : lo];
    Eigen::Vector3d p = a.position;
    if (lo != hi && e.t < truth[hi].t) {
      const double w = (e.t - truth[lo].t) / (truth[hi].t - truth[lo].t);
      p = (1.0 - w) * truth[lo].position + w * truth[hi].position;
    }
    out.t.push_back(e.t);
    out.errors.push_back(e.position - p);
    out.region.push_back(static_cast<int>(a.region));
    out.scene.push_back(static_cast<int>(a.scene));
  }
  return out;
}

}  // namespace ctxfuse::eval

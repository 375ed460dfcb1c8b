// Truth and labels: what a recording's reference system or the simulator knows and a sensor
// does not. Pipelines never see these records (they run on messages::SensorLog); only eval/, the
// training of classifiers from labelled logs, and the CLI's scoring read them.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "ctxfuse/sim/records.hpp"

namespace ctxfuse::eval {

namespace detail {
/// Index of the truth sample at or before t (the first one before the truth starts).
inline std::size_t sample_at_or_before(std::span<const sim::TruthSample> truth, double t) {
  const auto it = std::upper_bound(truth.begin(), truth.end(), t, [](double x, const sim::TruthSample& s) { return x < s.t; });
  return it == truth.begin() ? 0 : static_cast<std::size_t>(it - truth.begin()) - 1;
}
inline void require(std::span<const sim::TruthSample> truth) {
  if (truth.empty()) throw std::invalid_argument("eval: the truth is empty");
}
}  // namespace detail

/// True position at t, interpolated linearly between the samples around it (held at the ends).
inline Eigen::Vector3d position_at(std::span<const sim::TruthSample> truth, double t) {
  detail::require(truth);
  const std::size_t lo = detail::sample_at_or_before(truth, t);
  if (t <= truth[lo].t || lo + 1 == truth.size()) return truth[lo].position;
  const auto& a = truth[lo];
  const auto& b = truth[lo + 1];
  const double w = (t - a.t) / (b.t - a.t);
  return (1.0 - w) * a.position + w * b.position;
}

/// The region label (sim::Region as int) of the truth sample at or before t.
inline int region_at(std::span<const sim::TruthSample> truth, double t) {
  detail::require(truth);
  return static_cast<int>(truth[detail::sample_at_or_before(truth, t)].region);
}

/// Region labels at the given times: what trains a region recogniser from a labelled log.
inline std::vector<int> region_labels(std::span<const sim::TruthSample> truth, std::span<const double> times) {
  std::vector<int> out;
  out.reserve(times.size());
  for (double t : times) out.push_back(region_at(truth, t));
  return out;
}

}  // namespace ctxfuse::eval

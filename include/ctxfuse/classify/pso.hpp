// Particle swarm optimisation over a box: a global, derivative-free search for small parameter
// spaces such as (log2 C, log2 gamma) of an SVM. Deterministic for a given seed: the random
// numbers come from a fixed engine (std::mt19937_64) through our own uniform mapping, so the
// sequence does not depend on the standard library's distributions.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

namespace ctxfuse::classify {

struct PsoOptions {
  int swarm_size = 20;
  int iterations = 50;
  // Constriction-equivalent constants of Clerc and Kennedy (2002); inertia may decay linearly
  // from `inertia` to `final_inertia` over the iterations (equal values: constant inertia).
  double inertia = 0.7298;
  double final_inertia = 0.7298;
  double c1 = 1.49618;  // pull towards the particle's own best
  double c2 = 1.49618;  // pull towards the swarm's best
  // Velocity is clamped per coordinate to this fraction of the box width.
  double max_velocity_fraction = 0.5;
  std::uint64_t seed = 1;
};

template <int N>
struct PsoResult {
  Eigen::Matrix<double, N, 1> best_position;
  double best_value = std::numeric_limits<double>::infinity();
  int evaluations = 0;
};

namespace pso_detail {
inline double uniform01(std::mt19937_64& rng) {
  // 53 random bits -> [0, 1), identical on every platform.
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}
}  // namespace pso_detail

/// Does nothing: the default per-iteration observer.
struct PsoNoObserver {
  template <class Result>
  void operator()(int, const Result&) const {}
};

/// Minimises f over the box [lower, upper]. f(x) returning NaN counts as +infinity. Positions
/// that leave the box are clamped to it and their velocity component zeroed. `observe(it,
/// result)` is called after the initial swarm (it = 0) and after each iteration (it = 1 ..
/// iterations) with the best found so far.
template <int N, class F, class Observer = PsoNoObserver>
PsoResult<N> pso_minimize(F&& f, const Eigen::Matrix<double, N, 1>& lower, const Eigen::Matrix<double, N, 1>& upper,
                          const PsoOptions& options = {}, Observer&& observe = {}) {
  using Vec = Eigen::Matrix<double, N, 1>;
  if (options.swarm_size < 1 || options.iterations < 0) throw std::invalid_argument("pso: swarm_size >= 1 and iterations >= 0 required");
  if (!lower.allFinite() || !upper.allFinite() || (upper.array() < lower.array()).any())
    throw std::invalid_argument("pso: bounds must be finite with lower <= upper");
  std::mt19937_64 rng(options.seed);
  const Vec width = upper - lower;
  const Vec vmax = options.max_velocity_fraction * width;
  const auto n = static_cast<std::size_t>(options.swarm_size);
  std::vector<Vec> position(n), velocity(n), personal_best(n);
  std::vector<double> personal_value(n);
  PsoResult<N> result;
  result.best_position = lower + 0.5 * width;
  const auto evaluate = [&](const Vec& x) {
    ++result.evaluations;
    const double v = f(x);
    return std::isnan(v) ? std::numeric_limits<double>::infinity() : v;
  };
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < N; ++d) {
      position[i][d] = lower[d] + pso_detail::uniform01(rng) * width[d];
      velocity[i][d] = (2.0 * pso_detail::uniform01(rng) - 1.0) * vmax[d];
    }
    personal_best[i] = position[i];
    personal_value[i] = evaluate(position[i]);
    if (personal_value[i] < result.best_value) {
      result.best_value = personal_value[i];
      result.best_position = position[i];
    }
  }
  observe(0, result);
  for (int it = 0; it < options.iterations; ++it) {
    const double t = options.iterations > 1 ? static_cast<double>(it) / (options.iterations - 1) : 0.0;
    const double w = options.inertia + t * (options.final_inertia - options.inertia);
    for (std::size_t i = 0; i < n; ++i) {
      for (int d = 0; d < N; ++d) {
        const double r1 = pso_detail::uniform01(rng), r2 = pso_detail::uniform01(rng);
        double v = w * velocity[i][d] + options.c1 * r1 * (personal_best[i][d] - position[i][d]) +
                   options.c2 * r2 * (result.best_position[d] - position[i][d]);
        v = std::clamp(v, -vmax[d], vmax[d]);
        double x = position[i][d] + v;
        if (x < lower[d] || x > upper[d]) {
          x = std::clamp(x, lower[d], upper[d]);
          v = 0.0;
        }
        velocity[i][d] = v;
        position[i][d] = x;
      }
      const double value = evaluate(position[i]);
      if (value < personal_value[i]) {
        personal_value[i] = value;
        personal_best[i] = position[i];
        if (value < result.best_value) {
          result.best_value = value;
          result.best_position = position[i];
        }
      }
    }
    observe(it + 1, result);
  }
  return result;
}

/// Maximises f over the box; best_value is the maximum found (also in what `observe` sees).
template <int N, class F, class Observer = PsoNoObserver>
PsoResult<N> pso_maximize(F&& f, const Eigen::Matrix<double, N, 1>& lower, const Eigen::Matrix<double, N, 1>& upper,
                          const PsoOptions& options = {}, Observer&& observe = {}) {
  const auto flipped = [&](int it, const PsoResult<N>& r) {
    PsoResult<N> shown = r;
    shown.best_value = -r.best_value;
    observe(it, shown);
  };
  auto r = pso_minimize<N>([&](const Eigen::Matrix<double, N, 1>& x) { return -f(x); }, lower, upper, options, flipped);
  r.best_value = -r.best_value;
  return r;
}

}  // namespace ctxfuse::classify

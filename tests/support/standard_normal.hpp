// N standard normal draws in index order, for the tests' simulated noise. Not
// Vector(rng.normal(), rng.normal(), ...): the order in which function arguments are evaluated
// is unspecified (g++ goes right to left, clang left to right), so the same seed would give
// each compiler another run. draw_start: a Monte Carlo run's prior and the truth drawn from it.
#pragma once

#include <Eigen/Core>

#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/sim/random.hpp"

namespace ctxfuse::test {

template <int N>
Eigen::Matrix<double, N, 1> standard_normal(sim::Rng& rng) {
  Eigen::Matrix<double, N, 1> v;
  for (int i = 0; i < N; ++i) v(i) = rng.normal();
  return v;
}

/// A prior with independent components (means, standard deviations) and a truth drawn from it,
/// so the filter's first error is N(0, P0), as it assumes.
template <int N>
struct DrawnStart {
  Gaussian<N> prior;
  Eigen::Matrix<double, N, 1> truth;
};
template <int N>
DrawnStart<N> draw_start(const Eigen::Matrix<double, N, 1>& mean, const Eigen::Matrix<double, N, 1>& sd, sim::Rng& rng) {
  DrawnStart<N> s;
  s.prior.mean = mean;
  s.prior.cov = sd.cwiseProduct(sd).asDiagonal();
  s.truth = mean + sd.cwiseProduct(standard_normal<N>(rng));
  return s;
}

}  // namespace ctxfuse::test

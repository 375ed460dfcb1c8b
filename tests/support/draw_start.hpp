// A Monte Carlo run's start: a prior with independent components and the truth drawn from it
// (the draws in index order by sim::Rng::normals).
#pragma once

#include <Eigen/Core>

#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/sim/random.hpp"

namespace ctxfuse::test {

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
  s.truth = mean + sd.cwiseProduct(rng.normals<N>());
  return s;
}

}  // namespace ctxfuse::test

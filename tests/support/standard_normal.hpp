// N standard normal draws in index order, for the tests' simulated noise. Not
// Vector(rng.normal(), rng.normal(), ...): the order in which function arguments are evaluated
// is unspecified (g++ goes right to left, clang left to right), so the same seed would give
// each compiler another run.
#pragma once

#include <Eigen/Core>

#include "ctxfuse/sim/random.hpp"

namespace ctxfuse::test {

template <int N>
Eigen::Matrix<double, N, 1> standard_normal(sim::Rng& rng) {
  Eigen::Matrix<double, N, 1> v;
  for (int i = 0; i < N; ++i) v(i) = rng.normal();
  return v;
}

}  // namespace ctxfuse::test

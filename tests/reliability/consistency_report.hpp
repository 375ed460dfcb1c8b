// What the Monte Carlo consistency tests of tests/reliability/ share: the check they apply to
// every estimator, and one printed line per statistic, which docs/reliability.md quotes.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "ctxfuse/core/types.hpp"
#include "ctxfuse/eval/consistency.hpp"
#include "ctxfuse/sim/random.hpp"
#include "support/draw_start.hpp"

namespace ctxfuse::reliability {

// Each epoch's run-average lies in its 95 % band with probability 0.95 for a consistent
// filter; neighbouring epochs are correlated (the error is), so the fraction inside scatters
// more than a binomial count. 0.85 is the stated floor: ten points under the expectation.
inline constexpr double min_fraction_inside = 0.85;

struct Verdict {
  eval::BandCheck nees, nis;
  // The check, identical for every estimator: per-epoch NEES and NIS inside their bands at
  // >= min_fraction_inside of the epochs, and the time-averaged NIS inside its (exact, the
  // innovations being white) band.
  bool consistent() const {
    return nees.epochs_inside(min_fraction_inside) && nis.epochs_inside(min_fraction_inside) &&
           nis.time_average_inside();
  }
};


inline void print_check(const std::string& what, const char* stat, const eval::BandCheck& c) {
  std::printf("%s %s: epochs inside [%.3f, %.3f] %.3f, time average %.4f (band [%.4f, %.4f]), failures %zu\n",
              what.c_str(), stat, c.epoch_band.lower, c.epoch_band.upper, c.fraction_inside, c.time_average,
              c.time_band.lower, c.time_band.upper, c.failures);
  ::testing::Test::RecordProperty(what + "_" + stat + "_time_average", std::to_string(c.time_average));
  ::testing::Test::RecordProperty(what + "_" + stat + "_fraction_inside", std::to_string(c.fraction_inside));
}

inline void print_verdict(const std::string& what, const Verdict& v) {
  print_check(what, "NEES", v.nees);
  print_check(what, "NIS", v.nis);
  std::printf("%s: %s\n", what.c_str(), v.consistent() ? "consistent" : "REJECTED");
}

}  // namespace ctxfuse::reliability

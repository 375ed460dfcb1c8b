// The chi-square bands that the consistency tests judge by, against printed tables and, at the
// large degrees of freedom of a time average (runs x epochs x dimension, up to 1e5 here),
// against the Wilson-Hilferty approximation, whose relative error falls as dof^-1.5 (about
// 0.05 dof^-1.5 at these quantiles: 1.6e-6 at 1000, 1.5e-9 at 1e5).
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "ctxfuse/eval/consistency.hpp"

namespace {
using namespace ctxfuse;

double wilson_hilferty(double probability_z, int dof) {
  const double h = 2.0 / (9.0 * dof);
  return dof * std::pow(1.0 - h + probability_z * std::sqrt(h), 3);
}

TEST(ChiSquareBand, QuantilesFromTables) {
  // chi-square(1000): 0.025 -> 914.257, 0.975 -> 1089.531 (printed tables, 3 decimals).
  EXPECT_NEAR(chi_square_quantile(0.025, 1000), 914.257, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.975, 1000), 1089.531, 1e-3);
  // chi-square(200): 0.025 -> 162.728, 0.975 -> 241.058.
  EXPECT_NEAR(chi_square_quantile(0.025, 200), 162.728, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.975, 200), 241.058, 1e-3);
}

TEST(ChiSquareBand, LargeDegreesOfFreedomAgreeWithWilsonHilferty) {
  const double z = 1.959963984540054;  // standard normal 0.975 quantile
  for (int dof : {3000, 10000, 30000, 60000, 100000}) {
    const double tolerance = 0.1 * std::pow(dof, -1.5);  // twice the approximation's own error
    EXPECT_NEAR(chi_square_quantile(0.975, dof) / wilson_hilferty(z, dof), 1.0, tolerance) << dof;
    EXPECT_NEAR(chi_square_quantile(0.025, dof) / wilson_hilferty(-z, dof), 1.0, tolerance) << dof;
  }
}

TEST(ChiSquareBand, CheckBandsJudgesEveryEpochAndTheTimeAverage) {
  eval::MonteCarloAverage stat(3);
  // Two runs of dof 2: epoch averages 2.0, 2.0 and 9.0.
  for (double v : {1.0, 3.0}) stat.add(0, v);
  for (double v : {2.0, 2.0}) stat.add(1, v);
  for (double v : {8.0, 10.0}) stat.add(2, v);
  const auto c = eval::check_bands(stat, 2, 2);
  EXPECT_DOUBLE_EQ(c.epoch_band.lower, chi_square_quantile(0.025, 4) / 2.0);
  EXPECT_DOUBLE_EQ(c.time_band.upper, chi_square_quantile(0.975, 12) / 6.0);
  EXPECT_NEAR(c.fraction_inside, 2.0 / 3.0, 1e-15);  // 9.0 is above chi2_4(0.975) / 2 = 5.57
  EXPECT_NEAR(c.time_average, 26.0 / 6.0, 1e-15);
  EXPECT_TRUE(c.epochs_inside(0.6));
  EXPECT_FALSE(c.epochs_inside(0.7));
  EXPECT_FALSE(c.time_average_inside());  // 26 / 6 = 4.33 is above chi2_12(0.975) / 6 = 3.89
}

TEST(ChiSquareBand, MissingRunsAreRefused) {
  eval::MonteCarloAverage stat(2);
  stat.add(0, 1.0);
  stat.add(0, 1.0);
  stat.add(1, 1.0);
  EXPECT_THROW((void)eval::check_bands(stat, 1, 2), std::invalid_argument);
}

}  // namespace

// Dynamic alignment of the region pipeline (pipelines/region_imm/alignment.hpp) against hand
// computations: when a pair of fixes first qualifies, and the heading, velocity and
// covariances it gives.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "ctxfuse/pipelines/region_imm/alignment.hpp"

namespace {
using namespace ctxfuse;
namespace ri = pipelines::region_imm;

// A straight line at 30 deg from east, 6 m/s, one fix a second with sigma per axis `sd`.
Eigen::Vector2d on_line(double t) {
  const double a = std::numbers::pi / 6.0;
  return Eigen::Vector2d(100.0, -20.0) + 6.0 * t * Eigen::Vector2d(std::cos(a), std::sin(a));
}

TEST(RegionAlignment, WaitsUntilTheFixesPinTheHeadingThenUsesTheLongestBaseline) {
  const ri::Settings s;  // 5 m, 10 s, 5 deg, 1 s
  models::DynamicAligner aligner(s.alignment_options());
  const double sd = 1.0;
  const Eigen::Matrix2d cov = Eigen::Matrix2d::Identity() * sd * sd;
  // Heading sigma of a baseline of length L: sqrt(2) sd / L; 5 deg needs L >= 16.2 m, so the
  // pair (t = 0, t = 3 s: 18 m) is the first.
  std::optional<ri::Alignment> a;
  for (int k = 0; k <= 2; ++k) EXPECT_FALSE(aligner.add(k, on_line(k), cov).has_value()) << k;
  a = aligner.add(3.0, on_line(3.0), cov);
  ASSERT_TRUE(a.has_value());
  EXPECT_EQ(a->t, 3.0);
  EXPECT_EQ(a->position, on_line(3.0));
  EXPECT_NEAR(a->heading, std::numbers::pi / 6.0, 1e-12);
  EXPECT_NEAR(std::sqrt(a->heading_var), std::sqrt(2.0) * sd / 18.0, 1e-12);
  // Velocity over the last second: 6 m/s along the line; its covariance 2 sd^2 / 1 s^2.
  EXPECT_LT((a->velocity - 6.0 * Eigen::Vector2d(std::cos(std::numbers::pi / 6.0), std::sin(std::numbers::pi / 6.0))).norm(), 1e-12);
  EXPECT_NEAR(a->velocity_cov(0, 0), 2.0 * sd * sd, 1e-12);
  EXPECT_NEAR(a->velocity_cov(0, 1), 0.0, 1e-12);
  // Position: the last fix with the initial-position floor (3 m) above its own 1 m.
  EXPECT_EQ(a->position_cov(0, 0), s.init_position_sigma * s.init_position_sigma);
}

TEST(RegionAlignment, PreciseFixesAlignAtTheMinimumDistance) {
  ri::Settings s;
  models::DynamicAligner aligner(s.alignment_options());
  const Eigen::Matrix2d cov = Eigen::Matrix2d::Identity() * 1e-4;  // 1 cm
  EXPECT_FALSE(aligner.add(0.0, Eigen::Vector2d(0, 0), cov).has_value());
  EXPECT_FALSE(aligner.add(0.5, Eigen::Vector2d(0, 4.9), cov).has_value());  // not yet 5 m
  const auto a = aligner.add(1.0, Eigen::Vector2d(0, 5.2), cov);
  ASSERT_TRUE(a.has_value());
  EXPECT_NEAR(a->heading, std::numbers::pi / 2.0, 1e-12);  // north
  // The heading's own sigma (2 cm / 5.2 m) is below the 2 deg floor.
  EXPECT_NEAR(a->heading_var, std::pow(s.init_heading_sigma_deg * std::numbers::pi / 180.0, 2), 1e-15);
  // Velocity over the latest baseline of at least 1 s: the pair (0, 1 s).
  EXPECT_LT((a->velocity - Eigen::Vector2d(0.0, 5.2)).norm(), 1e-12);
}

TEST(RegionAlignment, FixesOlderThanTheSpanAndBadFixesDoNotCount) {
  ri::Settings s;
  s.align_max_span_s = 2.0;
  models::DynamicAligner aligner(s.alignment_options());
  const Eigen::Matrix2d cov = Eigen::Matrix2d::Identity() * 1e-4;
  EXPECT_FALSE(aligner.add(0.0, Eigen::Vector2d(0, 0), cov).has_value());
  // 10 m away but 3 s later: outside the span.
  EXPECT_FALSE(aligner.add(3.0, Eigen::Vector2d(10, 0), cov).has_value());
  // Non-finite, and not after the previous fix: ignored, not used as a partner.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(aligner.add(4.0, Eigen::Vector2d(nan, 0), cov).has_value());
  EXPECT_FALSE(aligner.add(3.0, Eigen::Vector2d(30, 0), cov).has_value());
  EXPECT_FALSE(aligner.add(2.5, Eigen::Vector2d(30, 0), cov).has_value());
  const auto a = aligner.add(4.5, Eigen::Vector2d(16, 0), cov);
  ASSERT_TRUE(a.has_value());
  EXPECT_NEAR(a->heading, 0.0, 1e-12);
  EXPECT_LT((a->velocity - Eigen::Vector2d(6.0 / 1.5, 0.0)).norm(), 1e-12);
}

TEST(RegionAlignment, InitialBeliefCarriesTheAlignmentAndTheBiasPriors) {
  const ri::Settings s;
  ri::Alignment a;
  a.position = Eigen::Vector2d(3, 4);
  a.position_cov << 9, 1, 1, 10;
  a.velocity = Eigen::Vector2d(-1, 2);
  a.velocity_cov << 2, 0.5, 0.5, 3;
  a.heading = 1.1;
  a.heading_var = 0.01;
  const auto b = models::planar_initial_belief(a, s);
  using L = ri::L;
  EXPECT_EQ(L::get<"p">(b.mean), a.position);
  EXPECT_EQ(L::get<"v">(b.mean), a.velocity);
  EXPECT_EQ(L::get<"psi">(b.mean)(0), 1.1);
  EXPECT_EQ(L::cov<"p">(b.cov), a.position_cov);
  EXPECT_EQ(L::cov<"v">(b.cov), a.velocity_cov);
  EXPECT_EQ(L::cov<"psi">(b.cov)(0, 0), 0.01);
  EXPECT_EQ(L::cov<"bg">(b.cov)(0, 0), s.init_gyro_bias_sigma * s.init_gyro_bias_sigma);
  EXPECT_EQ(L::cov<"ba">(b.cov), Eigen::Matrix2d::Identity() * s.init_accel_bias_sigma * s.init_accel_bias_sigma);
  EXPECT_EQ((L::cov<"p", "v">(b.cov)), Eigen::Matrix2d::Zero());
  EXPECT_EQ(b.mean.tail<3>(), Eigen::Vector3d::Zero());
}

}  // namespace

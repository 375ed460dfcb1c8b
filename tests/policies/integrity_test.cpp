// The snapshot integrity check (policies/integrity.hpp) against its definition: a fault after
// exactly `consecutive` snapshots in a row that fail both the chi-square test (threshold
// -2 ln(1 - p) for 2 dof, written out here) and the gross-error floor; neither test alone
// counts; an agreeing snapshot ends the run; the fault's velocity is the run's displacement
// over its time span; bad input is ignored without touching the run; bad options are refused.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "ctxfuse/policies/integrity.hpp"

namespace {
using namespace ctxfuse;
using policies::SnapshotIntegrity;
using policies::SnapshotIntegrityOptions;

const Eigen::Matrix2d kSmall = Eigen::Matrix2d::Identity() * 0.01;  // (0.1 m)^2

TEST(SnapshotIntegrity, ThresholdIsTheChiSquareQuantileForTwoDof) {
  // For 2 dof the chi-square CDF is 1 - exp(-x/2): the quantile is -2 ln(1 - p).
  const SnapshotIntegrity<2> m(SnapshotIntegrityOptions{.probability = 0.999});
  EXPECT_NEAR(m.threshold(), -2.0 * std::log(1.0 - 0.999), 1e-9);
}

TEST(SnapshotIntegrity, FaultAfterExactlyTheConsecutiveGrossDisagreements) {
  SnapshotIntegrity<2> m(SnapshotIntegrityOptions{.probability = 0.999, .min_error_m = 5.0, .consecutive = 3});
  const Eigen::Vector2d estimate(0.0, 0.0);
  // The snapshots move at (2, 1) m/s while the estimate, 20 m away, does not.
  const auto snap = [](double t) { return Eigen::Vector2d(20.0 + 2.0 * t, 1.0 * t); };
  EXPECT_FALSE(m.check(10.0, snap(10.0), kSmall, estimate, kSmall));
  EXPECT_EQ(m.run(), 1);
  EXPECT_FALSE(m.check(10.5, snap(10.5), kSmall, estimate, kSmall));
  EXPECT_EQ(m.run(), 2);
  const auto f = m.check(12.0, snap(12.0), kSmall, estimate, kSmall);
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->t, 12.0);
  EXPECT_EQ(f->position, snap(12.0));
  EXPECT_EQ(f->cov, kSmall);
  EXPECT_DOUBLE_EQ(f->span_s, 2.0);
  ASSERT_TRUE(f->velocity.has_value());
  EXPECT_NEAR((*f->velocity - Eigen::Vector2d(2.0, 1.0)).norm(), 0.0, 1e-12);
  EXPECT_EQ(m.run(), 0) << "a fault starts a new run";
}

TEST(SnapshotIntegrity, AnAgreeingSnapshotEndsTheRun) {
  SnapshotIntegrity<2> m(SnapshotIntegrityOptions{.consecutive = 3});
  const Eigen::Vector2d estimate(0.0, 0.0), far(30.0, 0.0), near(0.05, 0.0);
  EXPECT_FALSE(m.check(1.0, far, kSmall, estimate, kSmall));
  EXPECT_FALSE(m.check(2.0, far, kSmall, estimate, kSmall));
  EXPECT_FALSE(m.check(3.0, near, kSmall, estimate, kSmall));
  EXPECT_EQ(m.run(), 0);
  EXPECT_FALSE(m.check(4.0, far, kSmall, estimate, kSmall));
  EXPECT_FALSE(m.check(5.0, far, kSmall, estimate, kSmall));
  EXPECT_TRUE(m.check(6.0, far, kSmall, estimate, kSmall).has_value());
}

TEST(SnapshotIntegrity, NeitherTestAloneIsADisagreement) {
  SnapshotIntegrity<2> m(SnapshotIntegrityOptions{.probability = 0.999, .min_error_m = 5.0, .consecutive = 1});
  const Eigen::Vector2d estimate(0.0, 0.0);
  // 10 m apart, but the estimate claims 100 m: chi-square d2 = 100 / (1e4 + 0.01) < 13.8.
  EXPECT_FALSE(m.check(1.0, Eigen::Vector2d(10.0, 0.0), kSmall, estimate, Eigen::Matrix2d::Identity() * 1e4));
  EXPECT_LT(m.last_d2(), m.threshold());
  // 4 m apart with centimetre covariances: d2 = 16 / 0.02 = 800, but not a gross error.
  EXPECT_FALSE(m.check(2.0, Eigen::Vector2d(4.0, 0.0), kSmall, estimate, kSmall));
  EXPECT_NEAR(m.last_d2(), 16.0 / 0.02, 1e-9);
  // Both: 6 m apart, d2 = 1800.
  const auto f = m.check(3.0, Eigen::Vector2d(0.0, 6.0), kSmall, estimate, kSmall);
  ASSERT_TRUE(f.has_value());
  EXPECT_FALSE(f->velocity.has_value()) << "a run of one snapshot spans no time";
}

TEST(SnapshotIntegrity, BadInputIsIgnoredAndTheRunKept) {
  SnapshotIntegrity<2> m(SnapshotIntegrityOptions{.consecutive = 2});
  const Eigen::Vector2d estimate(0.0, 0.0), far(30.0, 0.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(m.check(1.0, far, kSmall, estimate, kSmall));
  ASSERT_EQ(m.run(), 1);
  EXPECT_FALSE(m.check(2.0, Eigen::Vector2d(nan, 0.0), kSmall, estimate, kSmall));
  EXPECT_FALSE(m.check(2.0, far, kSmall, Eigen::Vector2d(0.0, nan), kSmall));
  EXPECT_FALSE(m.check(nan, far, kSmall, estimate, kSmall));
  Eigen::Matrix2d indefinite;
  indefinite << 0.01, 0.0, 0.0, -1.0;
  EXPECT_FALSE(m.check(2.0, far, indefinite, estimate, kSmall));
  EXPECT_FALSE(m.check(0.5, far, kSmall, estimate, kSmall)) << "time going backwards";
  EXPECT_EQ(m.run(), 1);
  EXPECT_TRUE(m.check(2.0, far, kSmall, estimate, kSmall).has_value());
}

TEST(SnapshotIntegrity, OptionsOutOfRangeAreRefused) {
  EXPECT_THROW(SnapshotIntegrity<2>(SnapshotIntegrityOptions{.probability = 0.0}), std::invalid_argument);
  EXPECT_THROW(SnapshotIntegrity<2>(SnapshotIntegrityOptions{.probability = 1.0}), std::invalid_argument);
  EXPECT_THROW(SnapshotIntegrity<2>(SnapshotIntegrityOptions{.min_error_m = -1.0}), std::invalid_argument);
  EXPECT_THROW(SnapshotIntegrity<2>(SnapshotIntegrityOptions{.min_error_m = std::numeric_limits<double>::infinity()}),
               std::invalid_argument);
  EXPECT_THROW(SnapshotIntegrity<2>(SnapshotIntegrityOptions{.consecutive = 0}), std::invalid_argument);
}

}  // namespace

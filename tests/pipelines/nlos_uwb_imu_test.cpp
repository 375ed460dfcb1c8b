// The NLOS pipeline's IMU intake (pipelines/nlos_uwb/imu_smoother.hpp): how replay's pieces
// become an epoch's interval (clipped at both ends, gaps and refused samples covered by the
// sample before), and the smoother's start, which waits for an alignment from fixes.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "ctxfuse/pipelines/nlos_uwb/imu_smoother.hpp"

namespace {
using namespace ctxfuse;
namespace nu = pipelines::nlos_uwb;
using models::PlanarImu;

PlanarImu imu(double w) {
  PlanarImu u;
  u.yaw_rate = w;
  u.accel << 10.0 * w, 0.0;
  return u;
}

// Pieces of 10 ms starting at 0, 0.01, ...: sample k has yaw rate 0.1 k.
nu::ImuPieces hundred_hertz(int n) {
  nu::ImuPieces p;
  const models::PlanarImuModel m{};
  for (int k = 0; k < n; ++k) p.add(0.01 * k, 0.01, imu(0.1 * k), m);
  return p;
}

TEST(NlosImuPieces, IntervalIsClippedToTheStatesTimes) {
  const nu::ImuPieces p = hundred_hertz(10);
  models::PlanarImuInterval<16> u;
  ASSERT_TRUE(p.interval(0.035, 0.062, u));
  // 0.035-0.04 of sample 3, samples 4 and 5 whole, 0.06-0.062 of sample 6.
  ASSERT_EQ(u.count, 4);
  EXPECT_NEAR(u.dt[0], 0.005, 1e-15);
  EXPECT_NEAR(u.samples[0].yaw_rate, 0.3, 1e-15);
  EXPECT_NEAR(u.dt[1], 0.01, 1e-15);
  EXPECT_NEAR(u.samples[2].yaw_rate, 0.5, 1e-15);
  EXPECT_NEAR(u.dt[3], 0.002, 1e-15);
  EXPECT_NEAR(u.samples[3].yaw_rate, 0.6, 1e-15);
  EXPECT_NEAR(u.duration(), 0.027, 1e-15);
}

TEST(NlosImuPieces, GapsAndRefusedSamplesAreCoveredByTheSampleBefore) {
  nu::ImuPieces p;
  const models::PlanarImuModel m{};
  p.add(0.00, 0.01, imu(0.1), m);
  PlanarImu bad = imu(0.2);
  bad.yaw_rate = std::numeric_limits<double>::quiet_NaN();
  p.add(0.01, 0.01, bad, m);         // refused: 0.1 holds over it
  p.add(0.04, 0.01, imu(0.3), m);    // 0.02-0.04 has no piece: 0.1 holds over it too
  models::PlanarImuInterval<16> u;
  ASSERT_TRUE(p.interval(0.0, 0.06, u));
  double covered = 0.0, angle = 0.0;
  for (int k = 0; k < u.count; ++k) {
    covered += u.dt[static_cast<std::size_t>(k)];
    angle += u.samples[static_cast<std::size_t>(k)].yaw_rate * u.dt[static_cast<std::size_t>(k)];
  }
  EXPECT_NEAR(covered, 0.06, 1e-15);
  // 0.1 over 0-0.04, 0.3 over 0.04-0.06 (the last piece held past its end).
  EXPECT_NEAR(angle, 0.1 * 0.04 + 0.3 * 0.02, 1e-15);
  // Nothing accepted yet: a refused first sample has nothing to be replaced by.
  nu::ImuPieces none;
  none.add(0.0, 0.01, bad, m);
  EXPECT_EQ(none.size(), 0);
  EXPECT_FALSE(none.interval(0.0, 0.01, u));
}

TEST(NlosImuPieces, DroppingKeepsThePieceInForce) {
  nu::ImuPieces p = hundred_hertz(10);
  p.drop_before(0.055);
  EXPECT_EQ(p.size(), 5);  // pieces 5 (in force at 0.055) to 9
  models::PlanarImuInterval<16> u;
  ASSERT_TRUE(p.interval(0.055, 0.07, u));
  EXPECT_NEAR(u.samples[0].yaw_rate, 0.5, 1e-15);
}

TEST(NlosImuSmoother, StartsOnlyOnceTheFixesGiveAHeading) {
  const nu::Settings s;
  nu::ImuRangeSmoother<> est(s, nu::ImuFusionSettings{});
  const Eigen::Matrix2d P = Eigen::Matrix2d::Identity() * 0.01;
  // Moving north-east at 2 m/s, a fix every 0.1 s: 5 m are reached after 2.5 s.
  const Eigen::Vector2d dir = Eigen::Vector2d(1.0, 1.0).normalized();
  int refused = 0;
  for (int k = 0; k <= 40 && !est.started(); ++k) {
    const double t = 0.1 * k;
    const Status st = est.start(t, 2.0 * t * dir, P);
    if (!st.accepted()) {
      EXPECT_EQ(st.problem, Problem::time_not_set);
      ++refused;
    }
  }
  ASSERT_TRUE(est.started());
  EXPECT_GE(refused, 25);  // 2.5 s of fixes before the baseline exceeds 5 m
  EXPECT_NEAR(est.heading(), std::numbers::pi / 4, 1e-9);
  EXPECT_NEAR(est.velocity().x(), 2.0 * dir.x(), 1e-9);
  EXPECT_NEAR(est.velocity().y(), 2.0 * dir.y(), 1e-9);
  // A non-finite fix is refused as such.
  est.stop();
  EXPECT_EQ(est.start(1.0, Eigen::Vector2d(std::nan(""), 0.0), P).problem, Problem::non_finite_measurement);
}

TEST(NlosImuSmoother, EpochWithoutImuOrWithABrokenIntervalIsRefusedAndChangesNothing) {
  const nu::Settings s;
  nu::ImuRangeSmoother<> est(s, nu::ImuFusionSettings{});
  const Eigen::Matrix2d P = Eigen::Matrix2d::Identity() * 0.01;
  for (int k = 0; k <= 40 && !est.started(); ++k) (void)est.start(0.1 * k, Eigen::Vector2d(2.0 * 0.1 * k, 0.0), P);
  ASSERT_TRUE(est.started());
  const double t0 = est.time();
  const Eigen::Vector2d p0 = est.position();
  std::array<messages::UwbRange, 3> epoch{};
  for (int a = 0; a < 3; ++a) {
    epoch[static_cast<std::size_t>(a)].t = t0 + 0.1;
    epoch[static_cast<std::size_t>(a)].anchor_id = a;
    epoch[static_cast<std::size_t>(a)].anchor_position = Eigen::Vector3d(10.0 * a, 20.0, 2.0);
    epoch[static_cast<std::size_t>(a)].range_m = 20.0;
  }
  const std::array<bool, 3> attach{true, true, true};
  std::array<Status, 3> st{};
  // No IMU piece at all: nothing to build the factor from.
  EXPECT_EQ(est.apply_epoch(epoch, attach, st).problem, Problem::non_finite_input);
  EXPECT_EQ(est.time(), t0);
  EXPECT_EQ(est.position(), p0);
  // Only absurd samples (a 50 rad/s yaw rate): refused as pieces, so still nothing to use.
  messages::ImuSample spin;
  spin.gyro.z() = 50.0;
  for (int k = 0; k < 10; ++k) est.add_imu(t0 + 0.01 * k, 0.01, spin);
  EXPECT_EQ(est.apply_epoch(epoch, attach, st).problem, Problem::non_finite_input);
  EXPECT_EQ(est.time(), t0);
  // Good samples then make the same epoch a step.
  messages::ImuSample rest;
  rest.accel.z() = 9.81;
  for (int k = 0; k < 10; ++k) est.add_imu(t0 + 0.01 * k, 0.01, rest);
  EXPECT_TRUE(est.apply_epoch(epoch, attach, st).accepted());
  EXPECT_DOUBLE_EQ(est.time(), t0 + 0.1);
  // An epoch before the newest state: out of order, nothing changes.
  for (auto& r : epoch) r.t = t0 + 0.05;
  EXPECT_EQ(est.apply_epoch(epoch, attach, st).problem, Problem::out_of_order_time);
  EXPECT_DOUBLE_EQ(est.time(), t0 + 0.1);
}

}  // namespace

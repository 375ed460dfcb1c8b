// The detectors that decide when the INS constraints apply: static detection from raw IMU,
// the magnetometer's relative heading since a quasi-static-field epoch.
#include <gtest/gtest.h>

#include "ctxfuse/models/ins_motion.hpp"
#include "states.hpp"

namespace {
using namespace ctxfuse;
using namespace ctxfuse::models;
using test::kDeg;

// The defaults (0.5 s, 0.25 deg/s on the window's mean rate, 0.25 m/s^2 on its std of |f|) at
// 100 Hz: static once a full quiet window has come and only then; the mean rate of a slow turn
// and a bump in |f| end it; a non-finite sample or one not after the previous is ignored.
TEST(StaticDetector, StaticAfterAFullQuietWindowAndOnlyThen) {
  const Eigen::Vector3d f(0.1, -0.2, -9.79);
  const Eigen::Vector3d quiet(0.001 * kDeg, 0.0, 0.0);
  StaticDetector d;
  double t = 0.0;
  // The window's count is fixed from the rate once 50 samples (0.5 s at 100 Hz) have come.
  for (int i = 0; i < 49; ++i, t += 0.01) EXPECT_FALSE(d.push(t, quiet, f)) << i;
  EXPECT_TRUE(d.push(t, quiet, f));
  EXPECT_EQ(d.window_samples(), 50);
  EXPECT_TRUE(d.entered_static());
  t += 0.01;
  EXPECT_TRUE(d.push(t, quiet, f));
  EXPECT_FALSE(d.entered_static());  // only on the first static sample
  // A turn at 0.3 deg/s: the window's mean rate passes 0.25 deg/s after 42 of its 50 samples.
  int turned = 0;
  while (d.is_static() && turned < 100) {
    t += 0.01;
    d.push(t, Eigen::Vector3d(0.0, 0.0, 0.3 * kDeg), f);
    ++turned;
  }
  EXPECT_EQ(turned, 42);
  // A bump: |f| alternating +-0.3 m/s^2 has a std of 0.3 over the window.
  StaticDetector e;
  t = 0.0;
  for (int i = 0; i < 60; ++i, t += 0.01) e.push(t, Eigen::Vector3d::Zero(), f);
  ASSERT_TRUE(e.is_static());
  for (int i = 0; i < 50; ++i, t += 0.01) e.push(t, Eigen::Vector3d::Zero(), f * (1.0 + (i % 2 ? 0.3 : -0.3) / f.norm()));
  EXPECT_FALSE(e.is_static());
  // A non-finite sample, or one at the previous stamp, is ignored: not motion, not rest.
  StaticDetector n;
  t = 0.0;
  for (int i = 0; i < 60; ++i, t += 0.01) n.push(t, Eigen::Vector3d::Zero(), f);
  EXPECT_TRUE(n.push(t, Eigen::Vector3d(std::nan(""), 0, 0), f));
  EXPECT_TRUE(n.push(t - 0.01, Eigen::Vector3d(1.0, 0, 0), f));
  EXPECT_TRUE(n.is_static());
}

TEST(MagRelativeHeading, MeasuresTheHeadingChangeWhateverTheTilt) {
  const Eigen::Vector3d field_ned(22.0, 5.0, 42.0);
  auto attitude = [](double yaw, double pitch, double roll) {
    return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
        .toRotationMatrix();
  };
  const Eigen::Matrix3d C0 = attitude(10.0 * kDeg, 3.0 * kDeg, -2.0 * kDeg);
  MagRelativeHeading mag;
  mag.start(C0, C0.transpose() * field_ned);
  ASSERT_TRUE(mag.active());
  // The vehicle has turned by 35 deg and tilted otherwise; the filter's heading there is off
  // by 4 deg, but the measurement is the heading at k0 plus the magnetometer's change.
  const Eigen::Matrix3d C1 = attitude(45.0 * kDeg, -4.0 * kDeg, 5.0 * kDeg);
  const Eigen::Matrix3d C1_filter = attitude(49.0 * kDeg, -4.0 * kDeg, 5.0 * kDeg);
  const auto z = mag.heading(C1_filter, C1.transpose() * field_ned);
  ASSERT_TRUE(z.has_value());
  EXPECT_NEAR(*z, 45.0 * kDeg, 1e-9);
  // A field 10 % stronger (a passing truck, a bridge) ends the reference.
  EXPECT_FALSE(mag.heading(C1, 1.1 * (C1.transpose() * field_ned)).has_value());
  EXPECT_FALSE(mag.active());
}

}  // namespace

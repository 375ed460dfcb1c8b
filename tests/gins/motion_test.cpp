// The detectors that decide when the INS constraints apply: static detection from raw IMU,
// the magnetometer's relative heading since a quasi-static-field epoch.
#include <gtest/gtest.h>

#include "ctxfuse/models/ins_motion.hpp"
#include "states.hpp"

namespace {
using namespace ctxfuse;
using namespace ctxfuse::models;
constexpr double kDeg = test::kDeg;

TEST(StaticDetector, StaticAfterAFullQuietWindowAndOnlyThen) {
  StaticDetector d;  // 50 samples, 0.25 m/s^2, 0.25 deg/s
  const Eigen::Vector3d f(0.1, -0.2, -9.79);
  for (int i = 0; i < 49; ++i) EXPECT_FALSE(d.push(Eigen::Vector3d(0.001, 0.0, 0.0), f));
  EXPECT_TRUE(d.push(Eigen::Vector3d(0.001, 0.0, 0.0), f));
  EXPECT_TRUE(d.entered_static());
  EXPECT_TRUE(d.push(Eigen::Vector3d(0.001, 0.0, 0.0), f));
  EXPECT_FALSE(d.entered_static());  // only on the first static sample
  // A turn at 0.3 deg/s ends it, and so does a bump of 0.3 m/s^2.
  EXPECT_FALSE(d.push(Eigen::Vector3d(0.0, 0.0, 0.3 * kDeg), f));
  StaticDetector e;
  for (int i = 0; i < 60; ++i) e.push(Eigen::Vector3d::Zero(), f);
  ASSERT_TRUE(e.is_static());
  EXPECT_FALSE(e.push(Eigen::Vector3d::Zero(), f + Eigen::Vector3d(0.0, 0.0, -0.3)));
  // A non-finite sample is ignored, not taken as motion or rest.
  StaticDetector n;
  for (int i = 0; i < 60; ++i) n.push(Eigen::Vector3d::Zero(), f);
  EXPECT_TRUE(n.push(Eigen::Vector3d(std::nan(""), 0, 0), f));
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

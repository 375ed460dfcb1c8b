// The Allan deviation of the static start (pipelines/gins/static_start.hpp), which sets the
// IMU white-noise densities of pipelines/gins/settings.hpp, against closed forms: a rate ramp
// (sigma(tau) = R tau / sqrt(2) exactly), white noise of a known density (sigma(1 s) = N), a
// vibration that averages out within a cluster, and a static run interrupted by a gap.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "ctxfuse/pipelines/gins/static_start.hpp"
#include "ctxfuse/sim/random.hpp"

namespace {
using ctxfuse::pipelines::gins::AllanAccumulator;
using ctxfuse::pipelines::gins::StaticAccumulator;

TEST(AllanAccumulator, RampGivesRateTimesTauOverSqrtTwo) {
  const Eigen::Vector3d rate(0.3, -1.2, 2.5);  // units per second
  AllanAccumulator a(1.0);
  for (int i = 0; i <= 6000; ++i) {  // 100 Hz for 60 s; i / 100.0 is exact at whole seconds
    const double t = i / 100.0;
    a.add(t, rate * t);
  }
  EXPECT_EQ(a.differences(), 59u);  // 60 closed clusters (the sample at 60 s opens the 61st)
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(a.deviation()(k), std::abs(rate(k)) / std::numbers::sqrt2, 1e-12);
  AllanAccumulator two(2.0);
  for (int i = 0; i <= 6000; ++i) two.add(i / 100.0, rate * (i / 100.0));
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(two.deviation()(k), std::abs(rate(k)) * 2.0 / std::numbers::sqrt2, 1e-12);
}

TEST(AllanAccumulator, WhiteNoiseReadsItsDensityAtOneSecond) {
  // Density N per axis at 100 Hz: each sample's std is N sqrt(100 Hz). 4000 s give 3998
  // differences, so the estimate's relative std is about 1 / sqrt(2 * 3998) = 1.1 %.
  const Eigen::Vector3d density(0.05, 0.2, 0.01);
  ctxfuse::sim::Rng rng(11, ctxfuse::sim::Stream::imu);
  AllanAccumulator a(1.0);
  for (int i = 0; i < 400000; ++i) {
    Eigen::Vector3d x;
    for (int k = 0; k < 3; ++k) x(k) = density(k) * 10.0 * rng.normal();
    a.add(i / 100.0, x);
  }
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(a.deviation()(k) / density(k), 1.0, 0.04) << k;
}

TEST(AllanAccumulator, VibrationAveragesOutWhileItsScatterDoesNot) {
  // 2 deg/s at 23.7 Hz on one axis: per-sample std 2 / sqrt(2); a 1 s cluster's mean is at most
  // the last partial cycle's, 2 / (pi 23.7 Hz 1 s) = 0.027. The scatter read as white noise
  // (std / sqrt(100 Hz)) would claim 0.14 /sqrt(Hz), five times that.
  const double amplitude = 2.0, f = 23.7;
  StaticAccumulator s;
  for (int i = 0; i < 6000; ++i) {
    const double t = i / 100.0;
    s.add(t, Eigen::Vector3d(amplitude * std::sin(2.0 * std::numbers::pi * f * t), 0.0, 0.0), Eigen::Vector3d::Zero());
  }
  const auto st = s.stats();
  EXPECT_NEAR(st.gyro_std(0), amplitude / std::numbers::sqrt2, 0.01);
  EXPECT_LE(st.gyro_allan_1s(0), amplitude / (std::numbers::pi * f));
  EXPECT_GT(st.gyro_std(0) / 10.0, 5.0 * st.gyro_allan_1s(0));
  EXPECT_EQ(st.allan_differences, 58u);
}

TEST(AllanAccumulator, NoDifferenceSpansAGapAndNonFiniteSamplesAreSkipped) {
  // Static at 0 for 10 s, moving for 5 s (not added), static at 1 for 10 s: two chains of 10
  // clusters, 9 differences each, every one zero. A difference across the gap would be 1.
  AllanAccumulator a(1.0);
  for (int i = 0; i <= 1000; ++i) a.add(i / 100.0, Eigen::Vector3d::Zero());
  a.add(12.0, Eigen::Vector3d::Constant(NAN));
  for (int i = 1500; i <= 2500; ++i) a.add(i / 100.0, Eigen::Vector3d::Ones());
  EXPECT_EQ(a.differences(), 18u);
  EXPECT_EQ(a.deviation(), Eigen::Vector3d::Zero());
}

}  // namespace

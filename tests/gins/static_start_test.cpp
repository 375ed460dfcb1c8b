// The Allan deviation of the static start (pipelines/gins/static_start.hpp), which sets the
// IMU white-noise densities of pipelines/gins/settings.hpp, against closed forms: a rate ramp
// (sigma(tau) = R tau / sqrt(2) exactly), white noise of a known density (sigma(1 s) = N), a
// vibration that averages out within a cluster, and a static run interrupted by a gap; and the
// static test's thresholds from the static start (static_thresholds_from_rest) against white
// noise of a known std, the data sheet's floors and their false-alarm rate on fresh rest.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "ctxfuse/core/numerics.hpp"

#include "ctxfuse/pipelines/gins/static_start.hpp"
#include "ctxfuse/sim/random.hpp"

namespace {
using ctxfuse::pipelines::gins::AllanAccumulator;
using ctxfuse::pipelines::gins::StaticAccumulator;
using ctxfuse::models::StaticDetector;
using ctxfuse::pipelines::gins::static_thresholds_from_rest;
constexpr double kDegree = std::numbers::pi / 180.0;

// The window is half a second at any IMU rate: round(0.5 s x rate) samples, and a platform at
// rest is static once it has filled, not before; a turn of 1 deg/s (above the 0.25 deg/s
// threshold) is never static.
TEST(StaticDetector, TheWindowIsSecondsAtAnyRateRegularOrJittered) {
  const double g = 0.25 * std::numbers::pi / 180.0;
  for (double hz : {50.0, 100.0, 150.0, 400.0}) {
    StaticDetector rest(0.5, g, 0.25), turn(0.5, g, 0.25);
    int first_static = -1;
    for (int i = 0; i < 200; ++i) {
      const double t = 10.0 + i / hz;
      if (rest.push(t, Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, -9.8)) && first_static < 0) first_static = i;
      EXPECT_FALSE(turn.push(t, Eigen::Vector3d(0, 0, std::numbers::pi / 180.0), Eigen::Vector3d(0, 0, -9.8)));
    }
    const int n = static_cast<int>(std::lround(0.5 * hz));
    EXPECT_EQ(rest.window_samples(), n) << hz;
    EXPECT_EQ(first_static, n - 1) << hz;  // static on the sample that fills the window
  }
  // Steps uniform in [6, 8.5] ms (about 139 Hz): the count from the stamps, 0.5 s of them.
  ctxfuse::sim::Rng rng(7);
  StaticDetector j(0.5, g, 0.25);
  double t = 0.0;
  for (int i = 0; i < 400; ++i, t += rng.uniform(0.006, 0.0085)) j.push(t, Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, -9.8));
  EXPECT_NEAR(j.window_samples(), 0.5 / 0.00725, 5.0);
  // A sample not after the previous one, or non-finite, changes nothing.
  EXPECT_TRUE(j.is_static());
  EXPECT_TRUE(j.push(t - 1.0, Eigen::Vector3d::Constant(1.0), Eigen::Vector3d(0, 0, -9.8)));
  EXPECT_TRUE(j.push(t, Eigen::Vector3d::Constant(std::nan("")), Eigen::Vector3d(0, 0, -9.8)));
}

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

// An IMU at rest at 100 Hz: white noise of per-sample std gyro_sd (rad/s) and accel_sd (m/s^2)
// per axis about a rate bias and gravity, optionally a slow rotation about z.
struct RestImu {
  double gyro_sd, accel_sd;
  Eigen::Vector3d bias{5e-4, -3e-4, 2e-4};  // rad/s (0.036 deg/s in all)
  ctxfuse::sim::Rng rng{21, ctxfuse::sim::Stream::imu};
  void sample(Eigen::Vector3d& w, Eigen::Vector3d& f, double turn = 0.0) {
    for (int k = 0; k < 3; ++k) w(k) = bias(k) + gyro_sd * rng.normal();
    w(2) += turn;
    for (int k = 0; k < 3; ++k) f(k) = accel_sd * rng.normal();
    f(2) -= 9.80665;
  }
  /// The statistics of `samples` at rest from t = 0 (StaticAccumulator, 0.5 s windows).
  ctxfuse::pipelines::gins::StaticStats start(int samples) {
    StaticAccumulator acc(0.5);
    Eigen::Vector3d w, f;
    for (int i = 0; i < samples; ++i) {
      sample(w, f);
      acc.add(i / 100.0, w, f);
    }
    return acc.stats();
  }
};

// Closed forms for white noise: a 0.5 s window's mean rate has per-axis std sd / sqrt(50), so the
// rate threshold is sqrt(chi2_0.999(3)) = 4.03 times that times the upper-confidence factor of
// the Allan estimate (between 1 and 1.4 for the ~19 differences of 10 s); a window's std of |f|
// (near the vertical axis' noise at rest) scatters about accel_sd by accel_sd / sqrt(2 x 49).
TEST(StaticThresholds, FromAWhiteNoiseStartFollowTheNoise) {
  RestImu imu{0.05 * kDegree, 0.02};
  const auto st = imu.start(1000);
  EXPECT_EQ(st.window_differences, 18u);  // 20 windows in 10 s, the last still open
  EXPECT_EQ(st.f_windows, 19u);
  const auto th = static_thresholds_from_rest(st, 50, 5.0, 1e-3, 0.0038 * kDegree, 70e-6 * 9.80665);
  ASSERT_TRUE(th.has_value());
  EXPECT_TRUE(th->from_start);
  EXPECT_NEAR((th->gyro_bias - imu.bias).norm(), 0.0, 4.0 * 0.05 * kDegree / std::sqrt(1000.0) * std::sqrt(3.0));
  const double k3 = std::sqrt(ctxfuse::chi_square_quantile(0.999, 3));
  const double window_sd = 0.05 * kDegree / std::sqrt(50.0);
  EXPECT_GT(th->gyro / (k3 * window_sd), 0.9);
  EXPECT_LT(th->gyro / (k3 * window_sd), 1.9);
  // |f|'s window std: accel_sd times a factor near 1; the threshold adds z_0.999 = 3.09 of
  // its scatter, accel_sd / sqrt(98) each.
  EXPECT_NEAR(st.f_window_std_mean, 0.02, 0.003);
  EXPECT_GT(th->accel, 0.02 * (1.0 + 0.5 * 3.09 / std::sqrt(98.0)));
  EXPECT_LT(th->accel, 0.02 * (1.0 + 2.0 * 3.09 / std::sqrt(98.0)));
  // Shorter than min_duration_s: none.
  EXPECT_FALSE(static_thresholds_from_rest(imu.start(300), 50, 5.0, 1e-3, 0.0, 0.0).has_value());
}

// On fresh rest from the same IMU the calibrated detector keeps nearly every sample static (each
// window fails with probability about 2e-3), while a slow turn of 0.15 deg/s -- below the
// fallback's 0.25 deg/s, so a fallback detector calls it static -- is never static: on a quiet
// IMU the thresholds from its start see motion the fallback cannot.
TEST(StaticThresholds, CalibratedDetectorKeepsRestAndSeesASlowTurn) {
  RestImu imu{0.05 * kDegree, 0.02};
  const auto th = static_thresholds_from_rest(imu.start(1500), 50, 5.0, 1e-3, 0.0038 * kDegree, 70e-6 * 9.80665);
  ASSERT_TRUE(th.has_value());
  StaticDetector rest(0.5, 0.25 * kDegree, 0.25), turn(0.5, 0.25 * kDegree, 0.25),
      fallback(0.5, 0.25 * kDegree, 0.25);
  rest.calibrate(th->gyro, th->accel, th->gyro_bias);
  turn.calibrate(th->gyro, th->accel, th->gyro_bias);
  int rest_static = 0, turn_static = 0, fallback_static = 0, n = 0;
  Eigen::Vector3d w, f;
  for (int i = 0; i < 60000; ++i) {  // 600 s
    const double t = 20.0 + i / 100.0;
    imu.sample(w, f);
    rest_static += rest.push(t, w, f) ? 1 : 0;
    imu.sample(w, f, 0.15 * kDegree);
    turn_static += turn.push(t, w, f) ? 1 : 0;
    fallback_static += fallback.push(t, w, f) ? 1 : 0;
    n += i >= 49 ? 1 : 0;  // samples with a full window
  }
  EXPECT_GT(rest_static, 0.99 * n);
  EXPECT_EQ(turn_static, 0);
  EXPECT_GT(fallback_static, 0.99 * n);
}

// A start quieter than the part's data sheet (here noiseless) does not set thresholds that rest
// never passes: each is the data sheet's white noise through the same rule, in closed form.
TEST(StaticThresholds, ANoiselessStartGivesTheDataSheetFloors) {
  StaticAccumulator start(0.5);
  for (int i = 0; i < 1000; ++i) start.add(i / 100.0, Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, -9.80665));
  const double gd = 0.0038 * kDegree, ad = 70e-6 * 9.80665;
  const auto th = static_thresholds_from_rest(start.stats(), 50, 5.0, 1e-3, gd, ad);
  ASSERT_TRUE(th.has_value());
  EXPECT_NEAR(th->gyro, std::sqrt(ctxfuse::chi_square_quantile(0.999, 3)) * gd / std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(th->accel, ad * std::sqrt(50.0) * std::sqrt(ctxfuse::chi_square_quantile(0.999, 49) / 49.0), 1e-15);
}

}  // namespace

// models::PlanarImuIntervalModel, the IMU factor's process model over an interval of samples:
// its prediction against PlanarImuModel's steps chained by hand, its F against central
// differences, its Q against the covariance propagation written out for two samples, the
// heading carried across +-pi without a wrap, and the checks of its input.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "ctxfuse/models/planar_interval.hpp"

namespace {
using namespace ctxfuse;
using models::PlanarImu;
using models::PlanarLayout;
using PlanarL = PlanarLayout;
using X = Vector<PlanarL::size>;
using Model = models::PlanarImuIntervalModel<8>;

PlanarImu imu(double w, double ax, double ay) {
  PlanarImu u;
  u.yaw_rate = w;
  u.accel << ax, ay;
  return u;
}

X state(double psi) {
  X x;
  x << 3.0, -2.0, 4.0, 1.5, psi, 0.01, 0.05, -0.03;  // p, v, psi, bg, ba
  return x;
}

Model::Input turning_interval() {
  Model::Input u;
  u.add(imu(0.40, 1.2, 0.3), 0.010);
  u.add(imu(0.45, 1.0, 0.5), 0.012);
  u.add(imu(0.50, 0.8, 0.6), 0.008);
  return u;
}

TEST(PlanarImuInterval, PredictionChainsTheSamplesStepsWithAContinuousHeading) {
  const Model m{};
  const Model::Input u = turning_interval();
  // Start just below +pi, turning left: the heading passes pi and must not jump to -pi.
  const X x0 = state(std::numbers::pi - 0.003);
  X expected = x0;
  for (int k = 0; k < u.count; ++k) expected = m.step.predict(expected, u.samples[static_cast<std::size_t>(k)], u.dt[static_cast<std::size_t>(k)], nullptr);
  const X got = m.predict(x0, u, u.duration(), nullptr);
  // Heading: psi0 + sum (w - bg) dt, written out, beyond pi.
  const double psi = x0(4) + (0.40 - 0.01) * 0.010 + (0.45 - 0.01) * 0.012 + (0.50 - 0.01) * 0.008;
  EXPECT_GT(psi, std::numbers::pi);
  EXPECT_NEAR(got(PlanarL::offset<"psi">()), psi, 1e-15);
  // Every other element as the wrapped steps give it (the wrap does not change sin / cos).
  for (int i = 0; i < PlanarL::size; ++i) {
    if (i != PlanarL::offset<"psi">()) {
      EXPECT_NEAR(got(i), expected(i), 1e-14) << i;
    }
  }
  EXPECT_NEAR(models::wrap_angle(got(4)), expected(4), 1e-14);
}

TEST(PlanarImuInterval, TransitionEqualsCentralDifferences) {
  const Model m{};
  const Model::Input u = turning_interval();
  const X x0 = state(0.7);
  SquareMatrix<PlanarL::size> F;
  (void)m.predict(x0, u, u.duration(), &F);
  for (int j = 0; j < PlanarL::size; ++j) {
    const double h = 1e-6;
    X a = x0, b = x0;
    a(j) += h;
    b(j) -= h;
    const X col = (m.predict(a, u, u.duration(), nullptr) - m.predict(b, u, u.duration(), nullptr)) / (2 * h);
    for (int i = 0; i < PlanarL::size; ++i) EXPECT_NEAR(F(i, j), col(i), 1e-8) << i << "," << j;
  }
}

TEST(PlanarImuInterval, NoiseIsTheStepsNoisePropagatedThroughTheLaterSteps) {
  const Model m{};
  Model::Input u;
  u.add(imu(0.3, 1.0, 0.2), 0.01);
  u.add(imu(0.2, 0.5, -0.1), 0.02);
  const X x0 = state(0.4);
  SquareMatrix<PlanarL::size> F1, F2;
  const X x1 = m.step.predict(x0, u.samples[0], 0.01, &F1);
  (void)m.step.predict(x1, u.samples[1], 0.02, &F2);
  const SquareMatrix<PlanarL::size> Q1 = m.step.noise(x0, u.samples[0], 0.01), Q2 = m.step.noise(x1, u.samples[1], 0.02);
  const SquareMatrix<PlanarL::size> expected = F2 * Q1 * F2.transpose() + Q2;
  EXPECT_LT((m.noise(x0, u, 0.03) - expected).cwiseAbs().maxCoeff(), 1e-18);
  // One sample: the step's own Q.
  Model::Input one;
  one.add(u.samples[0], 0.01);
  EXPECT_EQ(m.noise(x0, one, 0.01), Q1);
}

TEST(PlanarImuInterval, FullIntervalMergesIntoItsLastSampleAndKeepsItsDuration) {
  models::PlanarImuInterval<2> u;
  u.add(imu(0.1, 1.0, 0.0), 0.01);
  u.add(imu(0.2, 2.0, 0.0), 0.01);
  u.add(imu(0.5, 5.0, 1.0), 0.03);  // full: merged into the last, weighted by span
  ASSERT_EQ(u.count, 2);
  EXPECT_DOUBLE_EQ(u.duration(), 0.05);
  EXPECT_DOUBLE_EQ(u.dt[1], 0.04);
  EXPECT_NEAR(u.samples[1].yaw_rate, (0.2 * 0.01 + 0.5 * 0.03) / 0.04, 1e-15);
  EXPECT_NEAR(u.samples[1].accel.x(), (2.0 * 0.01 + 5.0 * 0.03) / 0.04, 1e-15);
  EXPECT_NEAR(u.samples[1].accel.y(), 0.75, 1e-15);
}

TEST(PlanarImuInterval, ChecksRefuseWhatIsNotAnIntervalOfMotion) {
  const Model m{};
  const Model::Input good = turning_interval();
  EXPECT_EQ(m.check(good, good.duration()), Problem::none);
  EXPECT_EQ(m.check(good, good.duration() + 0.005), Problem::dt_above_maximum);  // does not cover the step
  EXPECT_EQ(m.check(Model::Input{}, 0.01), Problem::non_finite_input);           // no sample
  Model::Input spin = good;
  spin.samples[1].yaw_rate = 50.0;  // [rad/s]: not a car
  EXPECT_EQ(m.check(spin, spin.duration()), Problem::input_magnitude);
  Model::Input back = good;
  back.dt[2] = -0.008;
  EXPECT_EQ(m.check(back, back.duration()), Problem::non_positive_dt);
  Model::Input nan = good;
  nan.samples[0].accel.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(nan.is_finite());
}

}  // namespace

// Analytic Jacobians of the linear and kinematic models through the Jacobian battery
// (ctxfuse/testing/jacobians.hpp; the INS and planar models: jacobian_battery_test.cpp), and the
// INS mechanisation against closed forms.
#include <gtest/gtest.h>

#include "ctxfuse/models/ins.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/models/linear.hpp"
#include "ctxfuse/testing/jacobians.hpp"

namespace {
using namespace ctxfuse;

using L = Layout<StateBlock<"p", 3>, StateBlock<"v", 3>, StateBlock<"c", 1>>;

TEST(Jacobians, LinearProcessAndMeasurement) {
  models::LinearProcess<3, 2> lp;
  lp.F = SquareMatrix<3>::Random();
  lp.B = Matrix<3, 2>::Random();
  const Vector<3> x(1, -2, 0.5);
  const auto rp = ctxfuse::testing::check_transition(lp, x, Vector<2>(0.3, -0.7), 0.1);
  EXPECT_TRUE(rp) << rp;
  models::LinearMeasurement<2, 3> lm;
  lm.H = Matrix<2, 3>::Random();
  const auto rm = ctxfuse::testing::check_measurement(lm, x);
  EXPECT_TRUE(rm) << rm;
}

TEST(Jacobians, BlockObservationAndRange) {
  Vector<7> x;
  x << 1, 2, 3, -1, 0.5, 2, 7;
  const auto ro = ctxfuse::testing::check_measurement(models::BlockObservation<L, "v">{}, x);
  EXPECT_TRUE(ro) << ro;
  models::RangeToPoint<L, 3> range;
  range.anchor = {4, -2, 1};
  const auto rr = ctxfuse::testing::check_measurement(range, x);
  EXPECT_TRUE(rr) << rr;
}

TEST(InsModel, GaussMarkovDiscretisationIsExactUnderStepSplitting) {
  // Variance after T from zero must not depend on how T is split into steps:
  // sum_k decay^(2(n-1-k)) var(dt) = var(T).
  models::GaussMarkov gm{0.02, 50.0};
  const double T = 10.0;
  for (int n : {1, 10, 1000}) {
    const double dt = T / n;
    double var = 0.0;
    for (int k = 0; k < n; ++k) var = gm.decay(dt) * gm.decay(dt) * var + gm.variance(dt);
    EXPECT_NEAR(var, gm.variance(T), 1e-15);
  }
  models::GaussMarkov rw{0.02};
  EXPECT_DOUBLE_EQ(rw.variance(10.0), 0.02 * 0.02 * 10.0);
}

TEST(InsModel, ConstantRateRotatesByTheRateTimesTime) {
  models::Ins15Model m;
  models::InsState x;
  models::ImuSample u;
  u.gyro = {0.0, 0.0, 0.5};
  u.accel = -m.gravity;
  for (int k = 0; k < 100; ++k) x = m.predict(x, u, 0.01, nullptr);
  const Eigen::Quaterniond expected(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()));
  EXPECT_LT(x.q.angularDistance(expected), 1e-12);
  EXPECT_LT(x.p.norm(), 1e-12);
  // Constant forward acceleration in a body yawed by 90 deg moves along +y: p = a t^2 / 2.
  models::InsState y;
  y.q = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  models::ImuSample fwd;
  fwd.accel = Eigen::Vector3d(2.0, 0.0, 0.0) - m.gravity;
  for (int k = 0; k < 100; ++k) y = m.predict(y, fwd, 0.01, nullptr);
  EXPECT_NEAR(y.p.y(), 1.0, 1e-12);
  EXPECT_NEAR(y.p.x(), 0.0, 1e-12);
  EXPECT_NEAR(y.v.y(), 2.0, 1e-12);
}

}  // namespace

// Analytic Jacobians of every model against central differences.
#include <gtest/gtest.h>

#include "ctxfuse/models/ins.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/models/linear.hpp"
#include "support/numerical_jacobian.hpp"

namespace {
using namespace ctxfuse;
using test::central_jacobian;

using L = Layout<StateBlock<"p", 3>, StateBlock<"v", 3>, StateBlock<"c", 1>>;

TEST(Jacobians, ConstantVelocity) {
  models::ConstantVelocity<L, 3> cv;
  Vector<7> x;
  x << 1, 2, 3, -1, 0.5, 2, 7;
  SquareMatrix<7> F;
  cv.predict(x, {}, 0.3, &F);
  const auto f = [&](const Vector<7>& s) { return cv.predict(s, {}, 0.3, nullptr); };
  EXPECT_LT((F - central_jacobian<7, 7>(f, x)).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(Jacobians, LinearProcessAndMeasurement) {
  models::LinearProcess<3, 2> lp;
  lp.F = SquareMatrix<3>::Random();
  lp.B = Matrix<3, 2>::Random();
  const Vector<2> u(0.3, -0.7);
  const Vector<3> x(1, -2, 0.5);
  SquareMatrix<3> F;
  lp.predict(x, u, 0.1, &F);
  EXPECT_LT((F - central_jacobian<3, 3>([&](const Vector<3>& s) { return lp.predict(s, u, 0.1, nullptr); }, x))
                .cwiseAbs().maxCoeff(), 1e-9);
  models::LinearMeasurement<2, 3> lm;
  lm.H = Matrix<2, 3>::Random();
  Matrix<2, 3> H;
  lm.predict(x, &H);
  EXPECT_LT((H - central_jacobian<2, 3>([&](const Vector<3>& s) { return lm.predict(s, nullptr); }, x))
                .cwiseAbs().maxCoeff(), 1e-9);
}

TEST(Jacobians, BlockObservationAndRange) {
  Vector<7> x;
  x << 1, 2, 3, -1, 0.5, 2, 7;
  models::BlockObservation<L, "v"> obs;
  Matrix<3, 7> H;
  obs.predict(x, &H);
  EXPECT_LT((H - central_jacobian<3, 7>([&](const Vector<7>& s) { return obs.predict(s, nullptr); }, x))
                .cwiseAbs().maxCoeff(), 1e-9);

  models::RangeToPoint<L, 3> range;
  range.anchor = {4, -2, 1};
  Matrix<1, 7> Hr;
  range.predict(x, &Hr);
  EXPECT_LT((Hr - central_jacobian<1, 7>([&](const Vector<7>& s) { return range.predict(s, nullptr); }, x))
                .cwiseAbs().maxCoeff(), 1e-8);
}

models::InsState moving_state() {
  models::InsState x;
  x.p = {100.0, -20.0, 3.0};
  x.v = {8.0, 3.0, 0.1};
  x.q = Eigen::Quaterniond(Eigen::AngleAxisd(1.2, Eigen::Vector3d(0.1, 0.2, 1.0).normalized()));
  x.bg = {0.002, -0.001, 0.003};
  x.ba = {0.05, -0.08, 0.02};
  return x;
}

TEST(Jacobians, Ins15ErrorStateTransition) {
  // F = d(f(x [+] e) [-] f(x)) / de at e = 0.
  models::Ins15Model m;
  m.gyro_bias.tau = 300.0;  // exercise the Gauss-Markov decay too
  m.accel_bias.tau = 500.0;
  const models::InsState x = moving_state();
  models::ImuSample u;
  u.gyro = {0.3, -0.2, 0.8};
  u.accel = {1.5, -0.7, 9.5};
  for (double dt : {0.01, 0.2}) {
    SquareMatrix<15> F;
    const models::InsState fx = m.predict(x, u, dt, &F);
    const auto f = [&](const Vector<15>& e) { return m.difference(m.predict(m.inject(x, e), u, dt, nullptr), fx); };
    const SquareMatrix<15> F_num = central_jacobian<15, 15>(f, Vector<15>::Zero(), 1e-6);
    EXPECT_LT((F - F_num).cwiseAbs().maxCoeff(), 1e-7) << "dt " << dt << "\n" << (F - F_num);
  }
}

TEST(Jacobians, GnssPositionWithLeverArm) {
  models::Ins15Model m;
  models::GnssPosition<> gnss;
  gnss.lever_arm = {1.2, -0.4, 0.9};
  const models::InsState x = moving_state();
  Matrix<3, 15> H;
  gnss.predict(x, &H);
  const auto h = [&](const Vector<15>& e) { return gnss.predict(m.inject(x, e), nullptr); };
  EXPECT_LT((H - central_jacobian<3, 15>(h, Vector<15>::Zero())).cwiseAbs().maxCoeff(), 1e-8);
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

// Planar model and its measurements: analytic Jacobians against central differences
// (ctxfuse/testing/jacobians.hpp), the range and body velocity against hand values.
#include <gtest/gtest.h>

#include <cmath>

#include "ctxfuse/core/concepts.hpp"
#include "ctxfuse/models/ins_range.hpp"
#include "ctxfuse/models/planar.hpp"
#include "ctxfuse/testing/jacobians.hpp"

namespace {
using namespace ctxfuse;
using models::PlanarLayout;
using L = PlanarLayout;
using X = Vector<8>;

static_assert(VectorProcessModel<models::PlanarImuModel>);
static_assert(MeasurementModel<models::PlanarPosition, X, 8>);
static_assert(MeasurementModel<models::PlanarRange, X, 8>);
static_assert(MeasurementModel<models::PlanarBodyVelocity, X, 8>);
static_assert(MeasurementModel<models::ScaledNoise<models::PlanarRange>, X, 8>);

X sample_state() {
  X x;
  x << 3.0, -2.0, 1.5, 0.7, 0.6, 0.01, 0.05, -0.03;
  return x;
}

TEST(PlanarModel, ProcessJacobianMatchesCentralDifferences) {
  models::PlanarImuModel m;
  models::PlanarImu u;
  u.yaw_rate = 0.3;
  u.accel << 0.8, -0.4;
  for (double dt : {0.01, 0.1, 0.5}) {
    SquareMatrix<8> F;
    m.predict(sample_state(), u, dt, &F);
    const auto num = ctxfuse::testing::central_jacobian<8, 8>([&](const X& x) { return m.predict(x, u, dt, nullptr); }, sample_state());
    EXPECT_LT((F - num).cwiseAbs().maxCoeff(), 1e-8) << "dt " << dt;
  }
}

TEST(PlanarModel, StraightDriveByHand) {
  models::PlanarImuModel m;
  X x = X::Zero();
  L::get<"psi">(x)(0) = M_PI / 2;  // facing north
  L::get<"v">(x) << 0.0, 2.0;
  models::PlanarImu u;
  u.accel << 1.0, 0.0;  // forward
  const X y = m.predict(x, u, 0.5, nullptr);
  EXPECT_NEAR(L::get<"p">(y)(0), 0.0, 1e-15);
  EXPECT_NEAR(L::get<"p">(y)(1), 2.0 * 0.5 + 0.5 * 0.25, 1e-15);
  EXPECT_NEAR(L::get<"v">(y)(1), 2.5, 1e-15);
}

TEST(PlanarModel, MeasurementJacobiansMatchCentralDifferences) {
  const X x = sample_state();
  models::PlanarRange range;
  range.anchor << 10.0, 4.0, 3.0;
  range.tag_height = 1.2;
  Matrix<1, 8> Hr;
  const double r = range.predict(x, &Hr)(0);
  EXPECT_NEAR(r, std::sqrt(7.0 * 7.0 + 6.0 * 6.0 + 1.8 * 1.8), 1e-12);
  auto nr = ctxfuse::testing::central_jacobian<1, 8>([&](const X& s) { return range.predict(s, nullptr); }, x);
  EXPECT_LT((Hr - nr).cwiseAbs().maxCoeff(), 1e-8);

  models::PlanarBodyVelocity bv;
  Matrix<2, 8> Hv;
  const Vector<2> zv = bv.predict(x, &Hv);
  const double c = std::cos(0.6), s = std::sin(0.6);
  EXPECT_NEAR(zv(0), c * 1.5 + s * 0.7, 1e-15);
  EXPECT_NEAR(zv(1), -s * 1.5 + c * 0.7, 1e-15);
  auto nv = ctxfuse::testing::central_jacobian<2, 8>([&](const X& st) { return bv.predict(st, nullptr); }, x);
  EXPECT_LT((Hv - nv).cwiseAbs().maxCoeff(), 1e-8);

  models::PlanarPosition pos;
  Matrix<2, 8> Hp;
  pos.predict(x, &Hp);
  auto np = ctxfuse::testing::central_jacobian<2, 8>([&](const X& st) { return pos.predict(st, nullptr); }, x);
  EXPECT_LT((Hp - np).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(PlanarModel, DifferenceWrapsHeading) {
  models::PlanarImuModel m;
  X a = X::Zero(), b = X::Zero();
  a(L::offset<"psi">()) = M_PI - 0.05;
  b(L::offset<"psi">()) = -M_PI + 0.05;
  EXPECT_NEAR(m.difference(a, b)(L::offset<"psi">()), -0.1, 1e-12);
  EXPECT_NEAR(m.inject(a, m.difference(b, a))(L::offset<"psi">()), b(L::offset<"psi">()), 1e-12);
}

TEST(InsRange, JacobianMatchesCentralDifferencesOnTheManifold) {
  models::Ins15Model ins;
  models::InsState x;
  x.p << 1.0, 2.0, 0.5;
  x.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, 0.3, 0.9).normalized()));
  models::InsRange<> range;
  range.anchor << 8.0, -3.0, 2.5;
  range.lever_arm << 0.3, -0.1, 0.8;
  Matrix<1, 15> H;
  range.predict(x, &H);
  auto num = ctxfuse::testing::central_jacobian<1, 15>(
      [&](const Vector<15>& dx) { return range.predict(ins.inject(x, dx), nullptr); }, Vector<15>::Zero());
  EXPECT_LT((H - num).cwiseAbs().maxCoeff(), 1e-8);
}

}  // namespace

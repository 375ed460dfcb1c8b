// Every factor's analytic Jacobians against central differences of its own residual, and
// the difference Jacobians, at several points (not only the origin, where a wrong sign or a
// missing term can vanish).
#include <gtest/gtest.h>

#include <Eigen/LU>

#include "ctxfuse/filters/factors.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/models/linear.hpp"
#include "ctxfuse/testing/jacobians.hpp"

namespace {
using namespace ctxfuse;
using ctxfuse::testing::central_jacobian;

using PV3 = Layout<StateBlock<"p", 3>, StateBlock<"v", 3>>;
using PV2 = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;

Vector<6> state(int k) {
  Vector<6> x;
  x << 1.0 + k, -2.0 + 0.5 * k, 0.3 * k, 2.0 - k, 0.7, -0.4 * k;
  return x;
}

TEST(FactorJacobians, RangeMeasurementFactor) {
  models::RangeToPoint<PV3, 3> range;
  range.anchor = {5.0, -3.0, 2.5};
  range.sigma = 0.15;
  for (int k = 0; k < 4; ++k) {
    MeasurementFactor<6, models::RangeToPoint<PV3, 3>> f;
    ASSERT_TRUE(make_measurement_factor<6>(range, Vector<1>(6.0), state(k), f));
    Matrix<1, 6> J;
    const Vector<1> r = f.evaluate(state(k), &J);
    EXPECT_NEAR(r(0), ((state(k).head<3>() - range.anchor).norm() - 6.0) / 0.15, 1e-12);
    const auto num = central_jacobian<1, 6>([&](const Vector<6>& x) { return f.evaluate(x); }, state(k));
    EXPECT_LT((J - num).cwiseAbs().maxCoeff(), 1e-8) << k;
    EXPECT_GT(J.norm(), 1.0);  // 1/sigma times a unit vector: a zero Jacobian would pass a difference test too
  }
}

TEST(FactorJacobians, LinearMeasurementFactorWithCorrelatedNoise) {
  models::LinearMeasurement<2, 6> lm;
  lm.H << 1, 0.5, 0, 0, -1, 0, 0, 0, 2, 0.3, 0, 1;
  lm.R << 0.5, 0.1, 0.1, 0.2;
  MeasurementFactor<6, models::LinearMeasurement<2, 6>> f;
  ASSERT_TRUE(make_measurement_factor<6>(lm, Vector<2>(0.4, -1.0), state(1), f));
  // |r|^2 is the Mahalanobis distance of the innovation under R.
  const Vector<2> y = lm.H * state(2) - Vector<2>(0.4, -1.0);
  EXPECT_NEAR(f.evaluate(state(2)).squaredNorm(), y.dot(lm.R.inverse() * y), 1e-12);
  Matrix<2, 6> J;
  f.evaluate(state(2), &J);
  EXPECT_LT((J - central_jacobian<2, 6>([&](const Vector<6>& x) { return f.evaluate(x); }, state(2)))
                .cwiseAbs().maxCoeff(), 1e-8);
}

template <class Model>
void expect_motion_jacobians(const Model& model, const typename Model::Input& u, double dt) {
  MotionFactor<Model> f;
  ASSERT_TRUE(make_motion_factor(model, u, dt, state(0), f));
  for (int k = 0; k < 3; ++k) {
    const Vector<6> a = state(k), b = state(k + 1);
    SquareMatrix<6> Ja, Jb;
    const Vector<6> r = f.evaluate(a, b, &Ja, &Jb);
    // |r|^2 = d' Q^-1 d with d = b - f(a): the whitening against the plain formula.
    const Vector<6> d = b - model.predict(a, u, dt, nullptr);
    EXPECT_NEAR(r.squaredNorm(), d.dot(model.noise(a, u, dt).inverse() * d), 1e-9 * r.squaredNorm());
    const auto numa = central_jacobian<6, 6>([&](const Vector<6>& x) { return f.evaluate(x, b); }, a);
    const auto numb = central_jacobian<6, 6>([&](const Vector<6>& x) { return f.evaluate(a, x); }, b);
    EXPECT_LT((Ja - numa).cwiseAbs().maxCoeff(), 1e-6 * numa.cwiseAbs().maxCoeff()) << k;
    EXPECT_LT((Jb - numb).cwiseAbs().maxCoeff(), 1e-6 * numb.cwiseAbs().maxCoeff()) << k;
    if constexpr (AffineProcessModel<Model>) {
      // The declaration the smoother relies on (AffineFactorBlocks): the same Jacobians at
      // any pair of states, to the last bit.
      SquareMatrix<6> Ja0, Jb0;
      (void)f.evaluate(Vector<6>::Zero(), 100.0 * state(k + 2), &Ja0, &Jb0);
      EXPECT_EQ(Ja, Ja0) << k;
      EXPECT_EQ(Jb, Jb0) << k;
    }
  }
}

TEST(FactorJacobians, ConstantVelocityMotionFactor) {
  models::ConstantVelocity<PV3, 3> cv;
  cv.accel_psd = 0.8;
  expect_motion_jacobians(cv, NoInput{}, 0.1);
  expect_motion_jacobians(cv, NoInput{}, 1.3);
}

TEST(FactorJacobians, AccelerationDrivenMotionFactor) {
  models::AccelerationDriven<PV3, 3> imu;
  imu.accel_psd = 0.05;
  expect_motion_jacobians(imu, Vector<3>(0.4, -1.2, 0.1), 0.01);
  expect_motion_jacobians(imu, Vector<3>(2.0, 0.3, -0.5), 0.2);
}

TEST(FactorJacobians, LinearProcessMotionFactor) {
  models::LinearProcess<6, 2> lp;
  lp.F = SquareMatrix<6>::Identity();
  lp.F.topRightCorner<3, 3>().diagonal().setConstant(0.2);
  lp.F(0, 1) = 0.05;
  lp.B.bottomRows<2>().setIdentity();
  lp.Q = SquareMatrix<6>::Identity() * 0.3;
  lp.Q(1, 0) = lp.Q(0, 1) = 0.1;
  expect_motion_jacobians(lp, Vector<2>(0.5, -0.25), 0.2);
}

TEST(FactorJacobians, AccelerationDrivenMatchesConstantVelocityAtZeroInput) {
  models::AccelerationDriven<PV3, 3> imu;
  models::ConstantVelocity<PV3, 3> cv;
  EXPECT_EQ(imu.predict(state(2), Vector<3>::Zero(), 0.3, nullptr), cv.predict(state(2), {}, 0.3, nullptr));
  const Vector<6> moved = imu.predict(state(2), Vector<3>(1.0, 0.0, 0.0), 0.3, nullptr);
  EXPECT_NEAR(moved(0) - state(2)(0), state(2)(3) * 0.3 + 0.5 * 0.09, 1e-15);
  EXPECT_NEAR(moved(3) - state(2)(3), 0.3, 1e-15);
}

TEST(FactorJacobians, PriorFactor) {
  Gaussian<6> g;
  g.mean = state(3);
  SquareMatrix<6> A = SquareMatrix<6>::Random();
  g.cov = A * A.transpose() + SquareMatrix<6>::Identity();
  PriorFactor<6> f;
  ASSERT_TRUE(make_prior_factor(g, f));
  Matrix<6, 6> J;
  const Vector<6> r = f.evaluate(state(1), &J);
  const Vector<6> d = state(1) - g.mean;
  EXPECT_NEAR(r.squaredNorm(), d.dot(g.cov.inverse() * d), 1e-9 * r.squaredNorm());
  EXPECT_LT((J - central_jacobian<6, 6>([&](const Vector<6>& x) { return f.evaluate(x); }, state(1)))
                .cwiseAbs().maxCoeff(), 1e-8);
}

/// A model with its own difference (a wrapped angle in the last element), to exercise the
/// model-difference path of the motion factor.
struct WrappedHeading {
  static constexpr int dim = 2;
  using State = Vector<2>;
  using Input = NoInput;
  State predict(const State& x, const Input&, double dt, SquareMatrix<2>* F) const {
    if (F) *F << 1, 0, dt, 1;
    return State(x(0), x(1) + dt * x(0));
  }
  SquareMatrix<2> noise(const State&, const Input&, double dt) const { return SquareMatrix<2>::Identity() * dt; }
  Vector<2> difference(const State& a, const State& b, SquareMatrix<2>* Ja, SquareMatrix<2>* Jb) const {
    if (Ja) Ja->setIdentity();
    if (Jb) *Jb = -SquareMatrix<2>::Identity();
    return Vector<2>(a(0) - b(0), std::remainder(a(1) - b(1), 2.0 * 3.141592653589793));
  }
};

// What the smoother's fixed motion blocks are used for, and what not: a model that declares
// itself affine but has its own difference (a wrapped angle is not linear) stays general.
struct WrappedHeadingDeclaredAffine : WrappedHeading {
  static constexpr bool affine_in_state = true;
};
static_assert(AffineProcessModel<models::ConstantVelocity<PV3, 3>>);
static_assert(AffineProcessModel<models::AccelerationDriven<PV3, 3>>);
static_assert(AffineProcessModel<models::LinearProcess<6, 2>>);
static_assert(!AffineProcessModel<WrappedHeading> && !AffineProcessModel<WrappedHeadingDeclaredAffine>);

TEST(FactorJacobians, ModelDifferenceIsUsed) {
  WrappedHeading m;
  MotionFactor<WrappedHeading> f;
  ASSERT_TRUE(make_motion_factor(m, NoInput{}, 1.0, Vector<2>::Zero(), f));
  // Predicted heading 3.1 rad, next heading -3.1 rad: 0.083 rad apart through the wrap.
  const Vector<2> r = f.evaluate(Vector<2>(0.0, 3.1), Vector<2>(0.0, -3.1));
  EXPECT_NEAR(r(1), 2.0 * 3.141592653589793 - 6.2, 1e-12);
  SquareMatrix<2> Ja, Jb;
  f.evaluate(Vector<2>(0.2, 1.0), Vector<2>(0.1, 1.5), &Ja, &Jb);
  const auto numa = central_jacobian<2, 2>([&](const Vector<2>& x) { return f.evaluate(x, Vector<2>(0.1, 1.5)); },
                                           Vector<2>(0.2, 1.0));
  EXPECT_LT((Ja - numa).cwiseAbs().maxCoeff(), 1e-8);
}

TEST(FactorJacobians, FactoriesRefuseBadInput) {
  models::RangeToPoint<PV3, 3> range;
  MeasurementFactor<6, models::RangeToPoint<PV3, 3>> f;
  f.z(0) = 42.0;
  const auto before = f.z;
  EXPECT_EQ(make_measurement_factor<6>(range, Vector<1>(std::nan("")), state(0), f).problem,
            Problem::non_finite_measurement);
  EXPECT_EQ(make_measurement_factor<6>(range, Vector<1>(-1.0), state(0), f).problem, Problem::measurement_out_of_domain);
  range.sigma = 0.0;
  EXPECT_EQ(make_measurement_factor<6>(range, Vector<1>(1.0), state(0), f).problem,
            Problem::measurement_noise_not_positive_definite);
  EXPECT_EQ(f.z, before);

  models::ConstantVelocity<PV3, 3> cv;
  MotionFactor<models::ConstantVelocity<PV3, 3>> m;
  EXPECT_EQ(make_motion_factor(cv, NoInput{}, 0.0, state(0), m).problem, Problem::non_positive_dt);
  EXPECT_EQ(make_motion_factor(cv, NoInput{}, std::nan(""), state(0), m).problem, Problem::non_finite_dt);
  cv.accel_psd = 0.0;  // Q = 0: no soft factor exists
  EXPECT_EQ(make_motion_factor(cv, NoInput{}, 0.1, state(0), m).outcome, Outcome::invalid_input);
  models::AccelerationDriven<PV3, 3> imu;
  MotionFactor<models::AccelerationDriven<PV3, 3>> mi;
  EXPECT_EQ(make_motion_factor(imu, Vector<3>(0, std::nan(""), 0), 0.1, state(0), mi).problem, Problem::non_finite_input);
  EXPECT_EQ(make_motion_factor(imu, Vector<3>(0, 1e3, 0), 0.1, state(0), mi).problem, Problem::input_magnitude);

  Gaussian<6> g;
  g.cov(2, 2) = -1.0;
  PriorFactor<6> p;
  EXPECT_EQ(make_prior_factor(g, p).problem, Problem::covariance_not_positive_definite);
}

}  // namespace

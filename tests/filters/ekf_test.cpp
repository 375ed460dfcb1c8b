#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/models/linear.hpp"
#include "ctxfuse/models/on_layout.hpp"

namespace {
using namespace ctxfuse;

TEST(LinearKf, StaticScalarEqualsTheClosedFormRunningMean) {
  // x constant (F = 1, Q = 0), z_k = x + v_k, v ~ N(0, r), prior N(m0, p0):
  // P_k = 1 / (1/p0 + k/r) and x_k = P_k (m0/p0 + sum z / r).
  models::LinearProcess<1> f;
  models::LinearMeasurement<1, 1> h;
  h.H(0, 0) = 1.0;
  const double r = 0.25, p0 = 4.0, m0 = 1.0;
  h.R(0, 0) = r;
  Ekf<models::LinearProcess<1>> kf(f, {Vector<1>(m0), SquareMatrix<1>(p0)});
  const double z[] = {2.1, 1.7, 2.4, 1.9, 2.05, 2.2, 1.8};
  double sum = 0.0;
  for (int k = 1; k <= 7; ++k) {
    ASSERT_TRUE(kf.predict({}, 0.1));
    const Status s = kf.update(h, Vector<1>(z[k - 1]));
    ASSERT_TRUE(s);
    sum += z[k - 1];
    const double P = 1.0 / (1.0 / p0 + k / r);
    EXPECT_NEAR(kf.belief().cov(0, 0), P, 1e-14);
    EXPECT_NEAR(kf.belief().mean(0), P * (m0 / p0 + sum / r), 1e-13);
  }
}

TEST(LinearKf, OneStepMatchesHandComputation) {
  models::LinearProcess<2> f;
  f.F << 1, 1, 0, 1;
  models::LinearMeasurement<1, 2> h;
  h.H << 1, 0;
  h.R << 1;
  Gaussian<2> b{Vector<2>(0, 1), SquareMatrix<2>::Identity()};
  ASSERT_TRUE(ekf::predict(f, b, {}, 1.0));
  // x = (1, 1), P = [[2, 1], [1, 1]]
  EXPECT_EQ(b.mean, Vector<2>(1, 1));
  ASSERT_TRUE(ekf::update<2>(h, b, Vector<1>(2.0)));
  // S = 3, K = (2/3, 1/3), y = 1
  EXPECT_NEAR(b.mean(0), 5.0 / 3.0, 1e-15);
  EXPECT_NEAR(b.mean(1), 4.0 / 3.0, 1e-15);
  EXPECT_NEAR(b.cov(0, 0), 2.0 / 3.0, 1e-15);
  EXPECT_NEAR(b.cov(0, 1), 1.0 / 3.0, 1e-15);
  EXPECT_NEAR(b.cov(1, 0), 1.0 / 3.0, 1e-15);
  EXPECT_NEAR(b.cov(1, 1), 2.0 / 3.0, 1e-15);
}

TEST(LinearKf, LongSequenceMatchesTextbookEquationsInDynamicEigen) {
  // Constant velocity in 2-D with a position measurement, against the textbook filter written
  // plainly with MatrixXd, short-form covariance and an explicit inverse.
  using L = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;
  models::ConstantVelocity<L, 2> cv{0.5};
  models::BlockObservation<L, "p"> pos;
  pos.R << 0.4, 0.1, 0.1, 0.3;
  const double dt = 0.2;

  Gaussian<4> b{Vector<4>(0, 0, 1, -1), SquareMatrix<4>::Identity() * 10.0};
  Eigen::VectorXd x = b.mean;
  Eigen::MatrixXd P = b.cov;
  Eigen::MatrixXd F = Eigen::MatrixXd::Identity(4, 4);
  F(0, 2) = F(1, 3) = dt;
  const double q = 0.5;
  Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(4, 4);
  for (int i = 0; i < 2; ++i) {
    Q(i, i) = q * dt * dt * dt / 3;
    Q(i, i + 2) = Q(i + 2, i) = q * dt * dt / 2;
    Q(i + 2, i + 2) = q * dt;
  }
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(2, 4);
  H(0, 0) = H(1, 1) = 1;
  Eigen::MatrixXd R = pos.R;

  std::mt19937_64 rng(7);
  std::normal_distribution<double> n(0.0, 0.5);
  for (int k = 0; k < 200; ++k) {
    const Vector<2> z(0.3 * k * dt + n(rng), -0.2 * k * dt + n(rng));
    ASSERT_TRUE(ekf::predict(cv, b, {}, dt));
    ASSERT_TRUE(ekf::update<4>(pos, b, z));

    x = F * x;
    P = F * P * F.transpose() + Q;
    const Eigen::MatrixXd S = H * P * H.transpose() + R;
    const Eigen::MatrixXd K = P * H.transpose() * S.inverse();
    x = x + K * (Eigen::VectorXd(z) - H * x);
    P = (Eigen::MatrixXd::Identity(4, 4) - K * H) * P;

    ASSERT_LT((b.mean - x).cwiseAbs().maxCoeff(), 1e-10) << "step " << k;
    ASSERT_LT((b.cov - P).cwiseAbs().maxCoeff(), 1e-10) << "step " << k;
  }
}

TEST(Ekf, GateRejectsAFarOutlierAndReportsTheStatistic) {
  using L = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;
  models::BlockObservation<L, "p"> pos;
  pos.R = SquareMatrix<2>::Identity();
  Gaussian<4> b{Vector<4>::Zero(), SquareMatrix<4>::Identity()};
  const Gaussian<4> before = b;
  const policies::ChiSquareGate gate(0.99);
  const Status s = ekf::update<4>(pos, b, Vector<2>(30.0, 0.0), gate);
  EXPECT_EQ(s.outcome, Outcome::gated);
  EXPECT_NEAR(s.nis, 30.0 * 30.0 / 2.0, 1e-9);  // S = P + R = 2 I
  EXPECT_NEAR(s.gate_threshold, 9.2103, 1e-4);
  EXPECT_TRUE(std::isfinite(s.log_likelihood));
  EXPECT_EQ(b.mean, before.mean);
  EXPECT_EQ(b.cov, before.cov);
  // A near measurement passes the same gate.
  EXPECT_TRUE(ekf::update<4>(pos, b, Vector<2>(1.0, -1.0), gate));
}

TEST(Ekf, NonlinearRangeUpdateMatchesTextbookEkf) {
  using L = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;
  models::RangeToPoint<L, 2> range;
  range.anchor = Vector<2>(10.0, 5.0);
  range.sigma = 0.2;
  Gaussian<4> b{Vector<4>(1.0, 2.0, 0.5, 0.0), SquareMatrix<4>::Identity()};
  b.cov(0, 1) = b.cov(1, 0) = 0.3;
  const Eigen::Vector4d x0 = b.mean;
  const Eigen::Matrix4d P0 = b.cov;
  ASSERT_TRUE(ekf::update<4>(range, b, Vector<1>(9.0)));

  const Eigen::Vector2d d = x0.head<2>() - Eigen::Vector2d(10.0, 5.0);
  Eigen::RowVector4d H = Eigen::RowVector4d::Zero();
  H.head<2>() = d.transpose() / d.norm();
  const double S = H * P0 * H.transpose() + 0.04;
  const Eigen::Vector4d K = P0 * H.transpose() / S;
  EXPECT_LT((b.mean - (x0 + K * (9.0 - d.norm()))).cwiseAbs().maxCoeff(), 1e-13);
  EXPECT_LT((b.cov - (Eigen::Matrix4d::Identity() - K * H) * P0).cwiseAbs().maxCoeff(), 1e-13);
}

TEST(Ekf, LayoutAdapterAppliesASmallModelToALargerState) {
  using Small = Layout<StateBlock<"p", 2>>;
  using Big = Layout<StateBlock<"v", 2>, StateBlock<"psi", 1>, StateBlock<"p", 2>>;
  models::RangeToPoint<Small, 2> r_small;
  r_small.anchor = Vector<2>(3.0, 4.0);
  models::RangeToPoint<Big, 2> r_big;
  r_big.anchor = r_small.anchor;
  const auto adapted = models::on_layout<Big, Small>(r_small);

  Vector<5> x;
  x << 1, 2, 0.3, -1, 0.5;
  Matrix<1, 5> Ha, Hb;
  EXPECT_EQ(adapted.predict(x, &Ha), r_big.predict(x, &Hb));
  EXPECT_EQ(Ha, Hb);
  EXPECT_EQ(Ha.head<3>().sum(), 0.0);
}

TEST(Ekf, PredictToChecksTimeOrder) {
  models::LinearProcess<1> f;
  f.Q(0, 0) = 1.0;
  Ekf<models::LinearProcess<1>> kf(f, {Vector<1>(0.0), SquareMatrix<1>(1.0)});
  EXPECT_EQ(kf.predict_to(1.0, {}).problem, Problem::time_not_set);
  kf.set_time(1.0);
  ASSERT_TRUE(kf.predict_to(1.5, {}));
  EXPECT_EQ(kf.time(), 1.5);
  EXPECT_DOUBLE_EQ(kf.belief().cov(0, 0), 2.0);
  const Status back = kf.predict_to(1.2, {});
  EXPECT_EQ(back.outcome, Outcome::invalid_input);
  EXPECT_EQ(back.problem, Problem::out_of_order_time);
  EXPECT_EQ(kf.time(), 1.5);
  EXPECT_EQ(kf.predict_to(1.5, {}).problem, Problem::non_positive_dt);
}

// predict(u, dt) moves a set clock on by dt, so that predict and predict_to mixed predict each
// interval once: 1.0 -> 1.25 by dt, then predict_to(1.5) predicts the remaining 0.25 s. (This
// model's Q is per step: each of the three accepted steps adds 1 to the variance.) Without a
// clock, predict leaves the time unset.
TEST(Ekf, PredictByDtMovesASetClockOn) {
  models::LinearProcess<1> f;
  f.Q(0, 0) = 1.0;
  Ekf<models::LinearProcess<1>> kf(f, {Vector<1>(0.0), SquareMatrix<1>(1.0)});
  ASSERT_TRUE(kf.predict({}, 0.25));
  EXPECT_TRUE(std::isnan(kf.time()));
  kf.set_time(1.0);
  ASSERT_TRUE(kf.predict({}, 0.25));
  EXPECT_EQ(kf.time(), 1.25);
  ASSERT_TRUE(kf.predict_to(1.5, {}));
  EXPECT_EQ(kf.time(), 1.5);
  EXPECT_DOUBLE_EQ(kf.belief().cov(0, 0), 4.0);
  EXPECT_EQ(kf.predict({}, -0.1).problem, Problem::non_positive_dt);
  EXPECT_EQ(kf.time(), 1.5);
}

}  // namespace

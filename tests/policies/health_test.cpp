// Source health and the lock-out recovery (policies/health.hpp): the bookkeeping against its
// definition, the widening against P + sigma^2 on the block's diagonal written by hand, and the
// reason it exists: a filter whose covariance no longer covers its error is locked out by a
// tight gate for good, and comes back once the lock-out is noticed and P widened.
#include <gtest/gtest.h>

#include <cmath>

#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/federated.hpp"
#include "ctxfuse/filters/release.hpp"
#include "ctxfuse/models/ins.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/policies/gating.hpp"
#include "ctxfuse/policies/health.hpp"

namespace {
using namespace ctxfuse;
using policies::SourceHealth;
using policies::SourceHealthOptions;

Status gated() {
  Status s;
  s.outcome = Outcome::gated;
  return s;
}

TEST(SourceHealth, LockoutNeedsBothTheTimeoutAndTheRejectionCount) {
  SourceHealth h(SourceHealthOptions{2.0, 5});
  h.record(0.0, Status{});  // accepted at t = 0
  for (int k = 1; k <= 4; ++k) h.record(0.1 * k, gated());
  EXPECT_FALSE(h.lockout(10.0)) << "4 rejections are fewer than min_rejections";
  h.record(0.5, gated());
  EXPECT_EQ(h.rejections(), 5);
  // The run of rejections started at t = 0.1: it must last more than 2 s.
  EXPECT_FALSE(h.lockout(2.09));
  EXPECT_TRUE(h.lockout(2.11));
  h.record(2.1, Status{});
  EXPECT_FALSE(h.lockout(100.0)) << "one acceptance clears it";
}

TEST(SourceHealth, TheTimeoutRunsFromTheFirstRejectionWhenNothingWasEverAccepted) {
  SourceHealth h(SourceHealthOptions{1.0, 3});
  for (double t : {10.0, 10.2, 10.4}) h.record(t, gated());
  EXPECT_FALSE(h.lockout(11.0));
  EXPECT_TRUE(h.lockout(11.01));
}

TEST(SourceHealth, SilenceAndInvalidInputAreNotALockout) {
  SourceHealth h(SourceHealthOptions{1.0, 3});
  h.record(0.0, Status{});
  EXPECT_FALSE(h.lockout(1000.0)) << "a source that went silent";
  for (int k = 1; k <= 10; ++k) h.record(k, Status::invalid(Problem::non_finite_measurement));
  EXPECT_EQ(h.rejections(), 0);
  EXPECT_FALSE(h.lockout(1000.0)) << "invalid input says nothing about the filter";
}

TEST(SourceHealth, RecoveredStartsANewCount) {
  SourceHealth h(SourceHealthOptions{1.0, 2});
  for (double t : {0.0, 0.5, 1.0, 1.5}) h.record(t, gated());
  ASSERT_TRUE(h.lockout(1.6));
  h.recovered();
  EXPECT_FALSE(h.lockout(1.7));
  h.record(1.8, gated());
  h.record(1.9, gated());
  EXPECT_FALSE(h.lockout(2.79)) << "the timeout runs from the first rejection after the recovery";
  EXPECT_TRUE(h.lockout(2.81));
}

using L = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;

TEST(WidenBlock, AddsSigmaSquaredToTheBlockDiagonalOnly) {
  SquareMatrix<4> P;
  P << 4, 1, 0.5, 0.2,  //
      1, 3, 0.1, 0.3,   //
      0.5, 0.1, 2, 0.4,  //
      0.2, 0.3, 0.4, 1;
  SquareMatrix<4> expected = P;
  expected(2, 2) += 0.25;
  expected(3, 3) += 0.25;
  policies::widen_block<L, "v">(P, 0.5);
  EXPECT_EQ(P, expected);
}

// A 2-D constant-velocity filter told it is at the origin (sigma 1 cm) while the target sits
// 5 m away, with position fixes of sigma 0.3 m and a 0.999 gate: every fix is gated, forever.
// With the health bookkeeping and a widening of the position block the filter takes the fixes
// again and converges to the truth.
struct LockedRun {
  int accepted = 0;
  double final_error = 0.0;
  int recoveries = 0;
};

LockedRun run_locked_filter(bool with_recovery) {
  using Cv = models::ConstantVelocity<L, 2>;
  Cv cv;
  cv.accel_psd = 1e-6;  // P grows by (1.8 cm)^2 in 10 s: not enough to come back unaided
  Gaussian<4> b;
  b.mean.setZero();
  b.cov = SquareMatrix<4>::Identity() * 1e-4;
  Ekf<Cv, policies::ChiSquareGate> f(cv, b, FilterOptions{}, policies::ChiSquareGate(0.999));
  models::BlockObservation<L, "p"> fix;
  fix.R = SquareMatrix<2>::Identity() * 0.09;
  const Eigen::Vector2d truth(3.0, 4.0);
  SourceHealth health(SourceHealthOptions{2.0, 5});
  LockedRun out;
  for (int k = 1; k <= 100; ++k) {
    const double t = 0.1 * k;
    EXPECT_TRUE(f.predict({}, 0.1).accepted());
    const Status s = f.update(fix, Vector<2>(truth));
    out.accepted += s.accepted();
    health.record(t, s);
    if (with_recovery && health.lockout(t)) {
      auto widened = f.belief();
      policies::widen_block<L, "p">(widened.cov, 5.0);
      f.reset(widened);
      health.recovered();
      ++out.recoveries;
    }
  }
  out.final_error = (L::get<"p">(f.belief().mean) - truth).norm();
  return out;
}

TEST(LockoutRecovery, ATightGateLocksAFilterOutForGood) {
  const LockedRun r = run_locked_filter(false);
  EXPECT_EQ(r.accepted, 0);
  EXPECT_GT(r.final_error, 4.9);
}

TEST(LockoutRecovery, NoticingTheLockoutAndWideningPBringsTheFilterBack) {
  const LockedRun r = run_locked_filter(true);
  EXPECT_EQ(r.recoveries, 1);
  EXPECT_GT(r.accepted, 70);  // every fix after the recovery at t = 2.1 s
  EXPECT_LT(r.final_error, 0.3);
}

TEST(FederatedReset, ReplacesTheGlobalAndSharesItOutOrRejectsAndKeepsEverything) {
  using Cv = models::ConstantVelocity<L, 2>;
  Gaussian<4> b;
  b.mean << 1, 2, 3, 4;
  b.cov = SquareMatrix<4>::Identity();
  fkf::FederatedFilter<Cv, 2> f(Cv{}, b, {0.25, 0.75});
  Gaussian<4> g;
  g.mean << 5, 6, 7, 8;
  g.cov = SquareMatrix<4>::Identity() * 2.0;
  ASSERT_TRUE(f.reset(g).accepted());
  EXPECT_EQ(f.global().mean, g.mean);
  EXPECT_EQ(f.local(0).cov, g.cov / 0.25);
  EXPECT_EQ(f.local(1).cov, g.cov / 0.75);
  EXPECT_EQ(f.local(1).mean, g.mean);

  Gaussian<4> bad = g;
  bad.cov(0, 0) = -1.0;
  const Status s = f.reset(bad);
  EXPECT_EQ(s.outcome, Outcome::invalid_input);
  EXPECT_EQ(s.problem, Problem::covariance_not_positive_definite);
  bad = g;
  bad.mean(2) = std::nan("");
  EXPECT_EQ(f.reset(bad).problem, Problem::non_finite_state);
  EXPECT_EQ(f.global().mean, g.mean);
  EXPECT_EQ(f.global().cov, g.cov);
}

// variance_to_gate against its closed form in one dimension: y^2 / (S0 + a) = limit gives
// a = y^2 / limit - S0.
TEST(VarianceToGate, OneDimensionMatchesTheClosedForm) {
  const double limit = policies::ChiSquareGate(0.999).threshold(1);
  for (double y : {4.0, 10.0, 250.0}) {
    const double a = policies::variance_to_gate<1>(Vector<1>(y), SquareMatrix<1>(0.7), SquareMatrix<1>(1.0), limit);
    const double expected = y * y / limit - 0.7;
    EXPECT_NEAR(a, expected, 1e-9 * expected) << "y " << y;
  }
  // Inside the gate: nothing to add.
  EXPECT_EQ(policies::variance_to_gate<1>(Vector<1>(1.0), SquareMatrix<1>(0.7), SquareMatrix<1>(1.0), limit), 0.0);
  EXPECT_TRUE(std::isnan(policies::variance_to_gate<1>(Vector<1>(std::nan("")), SquareMatrix<1>(0.7), SquareMatrix<1>(1.0), limit)));
}

// In three dimensions with a correlated S0 and a block Jacobian that is not the identity: the
// widened innovation lies on the boundary (from the inside, within the bisection's width).
TEST(VarianceToGate, ThreeDimensionsPutTheInnovationOnTheBoundary) {
  const double limit = policies::ChiSquareGate(0.999).threshold(3);
  SquareMatrix<3> A;
  A << 1.0, 0.3, -0.2, 0.0, 0.8, 0.4, 0.1, 0.0, 1.5;
  const SquareMatrix<3> S0 = A * A.transpose() + 0.05 * SquareMatrix<3>::Identity();
  SquareMatrix<3> Hb;
  Hb << 1.0, 0.0, 0.2, 0.1, 1.0, 0.0, 0.0, -0.3, 1.0;
  const SquareMatrix<3> dS = Hb * Hb.transpose();
  const Vector<3> y(12.0, -7.0, 3.0);
  const double a = policies::variance_to_gate<3>(y, S0, dS, limit);
  const double nis = y.dot((S0 + a * dS).inverse() * y);
  EXPECT_GT(a, 0.0);
  EXPECT_LE(nis, limit);
  EXPECT_NEAR(nis, limit, 1e-9 * limit);
}

// eskf::release against the update of a covariance widened by hand by the same amount, and
// update_or_release's bookkeeping: three refused in a row, the fourth released.
TEST(EskfRelease, WidensThePositionBlockToTheGateAndUpdates) {
  const models::Ins15Model m;
  models::GnssPosition<> gnss;
  gnss.lever_arm = {0.5, -0.2, 1.1};
  gnss.R = SquareMatrix<3>::Identity() * 0.04;
  eskf::Belief<models::Ins15Model> b;
  b.nominal.p = {1.0, 2.0, 3.0};
  b.cov = SquareMatrix<15>::Identity() * 0.01;
  b.cov(0, 6) = b.cov(6, 0) = 0.002;  // position correlated with attitude
  const Vector<3> z(31.0, -18.0, 3.5);  // 36 m off a filter that believes 0.1 m
  const policies::ChiSquareGate gate(0.999);

  eskf::Belief<models::Ins15Model> gated = b;
  EXPECT_EQ(eskf::update(m, gnss, gated, z, gate).outcome, Outcome::gated);

  // By hand: H, y, S0, the amount, the widened update without a gate.
  Matrix<3, 15> H = Matrix<3, 15>::Zero();
  H.leftCols<3>().setIdentity();
  H.middleCols<3>(6) = -b.nominal.q.toRotationMatrix() * so3::skew(gnss.lever_arm);
  const Vector<3> y = z - (b.nominal.p + b.nominal.q.toRotationMatrix() * gnss.lever_arm);
  const SquareMatrix<3> S0 = H * b.cov * H.transpose() + gnss.R;
  const double a = policies::variance_to_gate<3>(y, S0, SquareMatrix<3>::Identity(), gate.threshold(3));
  eskf::Belief<models::Ins15Model> by_hand = b;
  by_hand.cov.topLeftCorner<3, 3>().diagonal().array() += a;
  ASSERT_TRUE(eskf::update(m, gnss, by_hand, z).accepted());

  eskf::Belief<models::Ins15Model> released = b;
  ASSERT_TRUE(eskf::release<"p">(m, gnss, released, z, gate).accepted());
  EXPECT_EQ(released.nominal.p, by_hand.nominal.p);
  EXPECT_EQ(released.cov, by_hand.cov);
  // The released fix is exactly on the boundary of the widened prior: S0 + a I.
  EXPECT_NEAR(y.dot((S0 + a * SquareMatrix<3>::Identity()).inverse() * y), gate.threshold(3), 1e-6);

  // Bookkeeping: refused three times (belief untouched), released the fourth time.
  policies::SourceHealth health(policies::SourceHealthOptions{0.0, 3});
  eskf::Belief<models::Ins15Model> f = b;
  bool was_released = true;
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(eskf::update_or_release<"p">(m, gnss, f, z, gate, health, 1.0 * k, &was_released).outcome, Outcome::gated);
    EXPECT_FALSE(was_released);
    EXPECT_EQ(f.cov, b.cov);
  }
  ASSERT_TRUE(eskf::update_or_release<"p">(m, gnss, f, z, gate, health, 3.0, &was_released).accepted());
  EXPECT_TRUE(was_released);
  EXPECT_EQ(f.nominal.p, by_hand.nominal.p);
  EXPECT_EQ(health.rejections(), 0);
}

}  // namespace

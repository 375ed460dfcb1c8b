// IMM against a plainly written textbook cycle (Bar-Shalom ch. 11.6.6) in dynamic Eigen, and
// the behaviour the IMM documents: probabilities sum to one, the right mode follows a jump,
// a far outlier cannot zero every mode, total rejection leaves the predicted probabilities,
// routing corrects only the modes that take a measurement.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "ctxfuse/filters/imm.hpp"
#include "ctxfuse/models/linear.hpp"
#include "ctxfuse/policies/mixing.hpp"

namespace {
using namespace ctxfuse;
namespace hana = boost::hana;
using Proc = models::LinearProcess<2>;
using Meas = models::LinearMeasurement<1, 2>;
using Eigen::MatrixXd;
using Eigen::VectorXd;

struct AnyTag {};

// ---- textbook reference, written out with dynamic matrices ------------------------------
struct RefMode {
  MatrixXd F, Q;
  VectorXd x;
  MatrixXd P;
};

struct RefImm {
  std::vector<RefMode> modes;
  VectorXd mu;
  MatrixXd T;  // rows = from

  void cycle(const MatrixXd& H, const MatrixXd& R, const VectorXd& z) {
    const int r = static_cast<int>(modes.size());
    VectorXd c = VectorXd::Zero(r);
    for (int j = 0; j < r; ++j)
      for (int i = 0; i < r; ++i) c(j) += T(i, j) * mu(i);
    std::vector<VectorXd> x0(r);
    std::vector<MatrixXd> P0(r);
    for (int j = 0; j < r; ++j) {
      x0[j] = VectorXd::Zero(2);
      for (int i = 0; i < r; ++i) x0[j] += T(i, j) * mu(i) / c(j) * modes[i].x;
      P0[j] = MatrixXd::Zero(2, 2);
      for (int i = 0; i < r; ++i) {
        const VectorXd d = modes[i].x - x0[j];
        P0[j] += T(i, j) * mu(i) / c(j) * (modes[i].P + d * d.transpose());
      }
    }
    VectorXd lambda(r);
    for (int j = 0; j < r; ++j) {
      auto& m = modes[j];
      const VectorXd xp = m.F * x0[j];
      const MatrixXd Pp = m.F * P0[j] * m.F.transpose() + m.Q;
      const MatrixXd S = H * Pp * H.transpose() + R;
      const MatrixXd K = Pp * H.transpose() * S.inverse();
      const VectorXd y = z - H * xp;
      m.x = xp + K * y;
      m.P = (MatrixXd::Identity(2, 2) - K * H) * Pp;
      const double q = (y.transpose() * S.inverse() * y)(0);
      lambda(j) = std::exp(-0.5 * q) / std::sqrt((2.0 * std::numbers::pi * S).determinant());
    }
    VectorXd post = lambda.cwiseProduct(c);
    mu = post / post.sum();
  }

  void combined(VectorXd& x, MatrixXd& P) const {
    x = VectorXd::Zero(2);
    for (std::size_t j = 0; j < modes.size(); ++j) x += mu(j) * modes[j].x;
    P = MatrixXd::Zero(2, 2);
    for (std::size_t j = 0; j < modes.size(); ++j) {
      const VectorXd d = modes[j].x - x;
      P += mu(j) * (modes[j].P + d * d.transpose());
    }
  }
};

Proc make_proc(double dt, double q) {
  Proc p;
  p.F << 1.0, dt, 0.0, 1.0;
  p.Q << q * dt * dt * dt / 3.0, q * dt * dt / 2.0, q * dt * dt / 2.0, q * dt;
  return p;
}

TEST(ImmCycle, MatchesTextbookToRoundOff) {
  // Three modes with different dynamics and noise; asymmetric transition matrix.
  Proc m0 = make_proc(1.0, 0.01), m1 = make_proc(1.0, 1.0), m2;
  m2.F << 0.9, 0.5, -0.1, 0.8;
  m2.Q << 0.3, 0.05, 0.05, 0.2;
  SquareMatrix<3> T;
  T << 0.90, 0.07, 0.03,
       0.15, 0.80, 0.05,
       0.02, 0.18, 0.80;
  Meas meas;
  meas.H << 1.0, 0.0;
  meas.R << 0.25;

  Gaussian<2> init;
  init.mean << 0.0, 1.0;
  init.cov << 1.0, 0.2, 0.2, 0.5;
  imm::ImmOptions<3> opts;
  opts.probability_floor = 0.0;  // the textbook has none
  auto filter = imm::Imm(policies::FixedTransition<3>(T),
                         hana::make_tuple(imm::make_mode(m0), imm::make_mode(m1), imm::make_mode(m2)), init,
                         Vector<3>(0.5, 0.3, 0.2), opts);
  // Distinct starting beliefs so that the very first mixing is not trivial.
  filter.template mode_belief<1>().mean << 0.5, 0.7;
  filter.template mode_belief<1>().cov << 2.0, -0.3, -0.3, 1.0;
  filter.template mode_belief<2>().mean << -0.4, 1.5;
  filter.template mode_belief<2>().cov << 0.7, 0.1, 0.1, 0.9;

  RefImm ref;
  for (int j = 0; j < 3; ++j) ref.modes.push_back({});
  ref.modes[0] = {m0.F, m0.Q, filter.template mode_belief<0>().mean, filter.template mode_belief<0>().cov};
  ref.modes[1] = {m1.F, m1.Q, filter.template mode_belief<1>().mean, filter.template mode_belief<1>().cov};
  ref.modes[2] = {m2.F, m2.Q, filter.template mode_belief<2>().mean, filter.template mode_belief<2>().cov};
  // Filled in place: assigning a fixed 3-vector temporary made g++ 12 warn (-Warray-bounds,
  // a false positive on Eigen's 4-wide AVX load in the x86-64-v3 build).
  ref.mu.resize(3);
  ref.mu << 0.5, 0.3, 0.2;
  ref.T = T;

  const double zs[] = {1.3, 2.1, 2.6, 4.9, 4.0};
  for (double z : zs) {
    ASSERT_TRUE(filter.mix());
    ASSERT_TRUE(filter.predict({}, 1.0).accepted());
    const auto res = filter.update(AnyTag{}, meas, Vector<1>(z));
    ASSERT_EQ(res.accepted_count, 3);
    filter.update_mode_probabilities();
    ref.cycle(meas.H, meas.R, VectorXd::Constant(1, z));

    for (int j = 0; j < 3; ++j) EXPECT_NEAR(filter.mode_probabilities()(j), ref.mu(j), 1e-12) << "mode " << j;
    EXPECT_NEAR(filter.mode_probabilities().sum(), 1.0, 1e-14);
    EXPECT_LT((filter.template mode_belief<0>().mean - ref.modes[0].x).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((filter.template mode_belief<1>().mean - ref.modes[1].x).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((filter.template mode_belief<2>().mean - ref.modes[2].x).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((filter.template mode_belief<0>().cov - ref.modes[0].P).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((filter.template mode_belief<1>().cov - ref.modes[1].P).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((filter.template mode_belief<2>().cov - ref.modes[2].P).cwiseAbs().maxCoeff(), 1e-12);
    VectorXd xc;
    MatrixXd Pc;
    ref.combined(xc, Pc);
    const auto comb = filter.combined();
    EXPECT_LT((comb.mean - xc).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((comb.cov - Pc).cwiseAbs().maxCoeff(), 1e-12);
  }
}

// State (p, 1): mode j moves p by drift_j per step, so the "1" carries the constant drift.
Proc drift_mode(double d) {
  Proc p;
  p.F << 1.0, d, 0.0, 1.0;
  p.Q << 0.01, 0.0, 0.0, 0.0;
  return p;
}

auto make_drift_imm(double floor = 1e-6) {
  Gaussian<2> init;
  init.mean << 0.0, 1.0;
  init.cov << 1.0, 0.0, 0.0, 1e-12;
  imm::ImmOptions<3> opts;
  opts.probability_floor = floor;
  return imm::Imm(policies::FixedTransition<3>(policies::sticky_transition<3>(0.95)),
                  hana::make_tuple(imm::make_mode(drift_mode(1.0)), imm::make_mode(drift_mode(0.0)),
                                   imm::make_mode(drift_mode(-1.0))),
                  init, Vector<3>::Constant(1.0 / 3.0), opts);
}

TEST(ImmBehaviour, FollowsAJumpInTheTrueModeWithinAFewSteps) {
  auto f = make_drift_imm();
  Meas meas;
  meas.H << 1.0, 0.0;
  meas.R << 0.09;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.3);
  double p = 0.0;
  int steps_to_switch = -1;
  for (int k = 0; k < 60; ++k) {
    const double drift = k < 30 ? 1.0 : -1.0;
    p += drift;
    ASSERT_TRUE(f.mix());
    ASSERT_TRUE(f.predict({}, 1.0).accepted());
    f.update(AnyTag{}, meas, Vector<1>(p + noise(rng)));
    f.update_mode_probabilities();
    EXPECT_NEAR(f.mode_probabilities().sum(), 1.0, 1e-12);
    if (k >= 5 && k < 30) {
      EXPECT_EQ(f.most_probable(), 0) << "step " << k;
    }
    if (k >= 30 && steps_to_switch < 0 && f.most_probable() == 2) steps_to_switch = k - 30;
    if (k >= 36) {
      EXPECT_EQ(f.most_probable(), 2) << "step " << k;
    }
  }
  EXPECT_GE(steps_to_switch, 0);
  EXPECT_LE(steps_to_switch, 3);
}

TEST(ImmBehaviour, FarOutlierDoesNotZeroEveryMode) {
  auto f = make_drift_imm(0.0);  // no floor: the log domain alone must keep the numbers alive
  Meas meas;
  meas.H << 1.0, 0.0;
  meas.R << 0.09;
  for (int k = 1; k <= 5; ++k) {
    ASSERT_TRUE(f.mix());
    ASSERT_TRUE(f.predict({}, 1.0));
    f.update(AnyTag{}, meas, Vector<1>(double(k)));
    f.update_mode_probabilities();
  }
  ASSERT_TRUE(f.mix());
  ASSERT_TRUE(f.predict({}, 1.0));
  // Each mode's likelihood is exp(-1e11) or so: zero in double precision for all of them.
  const auto res = f.update(AnyTag{}, meas, Vector<1>(1e6));
  ASSERT_TRUE(res.scored);
  for (int j = 0; j < 3; ++j) {
    EXPECT_TRUE(std::isfinite(res.mode[j].log_likelihood));
    EXPECT_LT(res.mode[j].log_likelihood, -1e9);
  }
  f.update_mode_probabilities();
  const auto mu = f.mode_probabilities();
  ASSERT_TRUE(mu.allFinite());
  EXPECT_NEAR(mu.sum(), 1.0, 1e-12);
  // So far out, log N ~ -y^2 / (2 S): the mode with the broadest innovation covariance
  // explains the outlier least badly and takes the probability; the others stay finite.
  int best = 0;
  for (int j = 1; j < 3; ++j)
    if (res.mode[j].log_likelihood > res.mode[best].log_likelihood) best = j;
  EXPECT_EQ(f.most_probable(), best);
  EXPECT_GT(mu(best), 0.99);
}

TEST(ImmBehaviour, TotalRejectionKeepsPredictedProbabilities) {
  Gaussian<2> init;
  init.mean << 0.0, 1.0;
  init.cov << 1.0, 0.0, 0.0, 1e-12;
  auto f = imm::Imm(policies::FixedTransition<3>(policies::sticky_transition<3>(0.9)),
                    hana::make_tuple(imm::make_mode(drift_mode(1.0), imm::AcceptsAll{}, policies::ChiSquareGate(0.999)),
                                     imm::make_mode(drift_mode(0.0), imm::AcceptsAll{}, policies::ChiSquareGate(0.999)),
                                     imm::make_mode(drift_mode(-1.0), imm::AcceptsAll{}, policies::ChiSquareGate(0.999))),
                    init, Vector<3>(0.6, 0.3, 0.1));
  Meas meas;
  meas.H << 1.0, 0.0;
  meas.R << 0.09;
  ASSERT_TRUE(f.mix());
  const Vector<3> c = f.predicted_probabilities();
  // c_j = sum_i p_ij mu_i by hand: 0.9*0.6+0.05*0.3+0.05*0.1 = 0.56, ...
  EXPECT_NEAR(c(0), 0.56, 1e-15);
  EXPECT_NEAR(c(1), 0.05 * 0.6 + 0.9 * 0.3 + 0.05 * 0.1, 1e-15);
  ASSERT_TRUE(f.predict({}, 1.0));
  const auto before = f.mode_belief<1>();
  const auto res = f.update(AnyTag{}, meas, Vector<1>(500.0));
  EXPECT_EQ(res.accepted_count, 0);
  EXPECT_FALSE(res.scored);
  for (int j = 0; j < 3; ++j) EXPECT_EQ(res.mode[j].outcome, Outcome::gated);
  EXPECT_EQ(f.mode_belief<1>().mean, before.mean);
  f.update_mode_probabilities();
  EXPECT_LT((f.mode_probabilities() - c).cwiseAbs().maxCoeff(), 1e-15);
}

struct GnssTag {};
struct UwbTag {};

TEST(ImmRouting, OnlyTakersAreCorrectedButEveryModeIsScored) {
  Gaussian<2> init;
  init.mean << 0.0, 1.0;
  init.cov << 1.0, 0.0, 0.0, 1e-12;
  auto f = imm::Imm(policies::FixedTransition<3>(policies::sticky_transition<3>(0.9)),
                    hana::make_tuple(imm::make_mode(drift_mode(0.0), imm::Accepts<GnssTag>{}),
                                     imm::make_mode(drift_mode(0.0), imm::Accepts<GnssTag, UwbTag>{}),
                                     imm::make_mode(drift_mode(0.0), imm::Accepts<UwbTag>{})),
                    init, Vector<3>::Constant(1.0 / 3.0));
  Meas meas;
  meas.H << 1.0, 0.0;
  meas.R << 0.09;
  ASSERT_TRUE(f.mix());
  ASSERT_TRUE(f.predict({}, 1.0));
  const auto b2 = f.mode_belief<2>();
  auto res = f.update(GnssTag{}, meas, Vector<1>(0.5));
  EXPECT_TRUE(res.taken[0]);
  EXPECT_TRUE(res.taken[1]);
  EXPECT_FALSE(res.taken[2]);
  EXPECT_EQ(f.mode_belief<2>().mean, b2.mean);  // not corrected ...
  EXPECT_TRUE(std::isfinite(f.cycle_log_likelihood()(2)));
  EXPECT_NE(f.cycle_log_likelihood()(2), 0.0);  // ... but scored
  EXPECT_NE(f.mode_belief<0>().mean, b2.mean);

  // Runtime mask: UWB allowed for mode 1 only (mode 2 masked out, mode 0 does not take UWB).
  const auto b1 = f.mode_belief<1>();
  res = f.update(UwbTag{}, meas, Vector<1>(0.4), 0b010u);
  EXPECT_FALSE(res.taken[0]);
  EXPECT_TRUE(res.taken[1]);
  EXPECT_FALSE(res.taken[2]);
  EXPECT_NE(f.mode_belief<1>().mean, b1.mean);
  EXPECT_EQ(f.mode_belief<2>().mean, b2.mean);

  // A mask no mode matches: nothing taken, nothing scored.
  const Vector<3> ll = f.cycle_log_likelihood();
  res = f.update(UwbTag{}, meas, Vector<1>(0.4), 0b001u);
  EXPECT_EQ(res.taken_count, 0);
  EXPECT_FALSE(res.scored);
  EXPECT_EQ(f.cycle_log_likelihood(), ll);
}

TEST(ImmRouting, InvalidMeasurementChangesNothing) {
  auto f = make_drift_imm();
  Meas meas;
  meas.H << 1.0, 0.0;
  meas.R << 0.09;
  ASSERT_TRUE(f.mix());
  ASSERT_TRUE(f.predict({}, 1.0));
  const auto b0 = f.mode_belief<0>();
  const auto res = f.update(AnyTag{}, meas, Vector<1>(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_EQ(res.problem, Problem::non_finite_measurement);
  EXPECT_FALSE(res.scored);
  EXPECT_EQ(f.mode_belief<0>().mean, b0.mean);
  EXPECT_EQ(f.cycle_log_likelihood(), Vector<3>::Zero());
  // A bad time step is refused by every mode and changes none.
  EXPECT_EQ(f.predict({}, -1.0).problem, Problem::non_positive_dt);
  EXPECT_EQ(f.mode_belief<0>().mean, b0.mean);
}

TEST(ImmBehaviour, FloorKeepsEveryModeAlive) {
  auto f = make_drift_imm(1e-4);
  Meas meas;
  meas.H << 1.0, 0.0;
  meas.R << 0.01;
  for (int k = 1; k <= 30; ++k) {
    ASSERT_TRUE(f.mix());
    ASSERT_TRUE(f.predict({}, 1.0));
    f.update(AnyTag{}, meas, Vector<1>(double(k)));
    f.update_mode_probabilities();
    EXPECT_GE(f.mode_probabilities().minCoeff(), 1e-4 - 1e-16);
    EXPECT_NEAR(f.mode_probabilities().sum(), 1.0, 1e-12);
  }
  EXPECT_NEAR(f.mode_probabilities()(2), 1e-4, 1e-16);
}

}  // namespace

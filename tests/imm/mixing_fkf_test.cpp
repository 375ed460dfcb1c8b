// Mixing policies (region paper eq. 36-39) against hand-counted matrices, the w_m = 0
// reduction to the fixed matrix, and the federated fusion against the information-form
// formula written with explicit inverses.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <numbers>

#include "ctxfuse/filters/federated.hpp"
#include "ctxfuse/filters/imm.hpp"
#include "ctxfuse/models/linear.hpp"
#include "ctxfuse/models/planar.hpp"
#include "ctxfuse/policies/mixing.hpp"

namespace {
using namespace ctxfuse;
namespace hana = boost::hana;

SquareMatrix<3> asymmetric_prior() {
  SquareMatrix<3> P;
  P << 0.90, 0.07, 0.03,
       0.15, 0.80, 0.05,
       0.02, 0.18, 0.80;
  return P;
}

TEST(RegionAdaptive, RecognisedMatrixCountsTransitions) {
  policies::RegionAdaptiveTransition<3> pol(asymmetric_prior(), 0.4, 0.6);
  for (int l : {0, 0, 1, 1, 2, 2, 2, 1}) pol.observe_region(l);
  // transitions: 0->0, 0->1, 1->1, 1->2, 2->2, 2->2, 2->1
  SquareMatrix<3> M;
  M << 0.5, 0.5, 0.0,
       0.0, 0.5, 0.5,
       0.0, 1.0 / 3.0, 2.0 / 3.0;
  EXPECT_LT((pol.recognised_matrix() - M).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((pol.matrix() - (0.4 * asymmetric_prior() + 0.6 * M)).cwiseAbs().maxCoeff(), 1e-15);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(pol.matrix().row(i).sum(), 1.0, 1e-15);
}

TEST(RegionAdaptive, UnknownLabelBreaksTheChainAndEmptyRowsPersist) {
  policies::RegionAdaptiveTransition<3> pol(asymmetric_prior(), 0.5, 0.5);
  for (int l : {0, -1, 2, 2}) pol.observe_region(l);
  EXPECT_EQ(pol.counts().sum(), 1.0);  // only 2->2
  const SquareMatrix<3> M = pol.recognised_matrix();
  EXPECT_EQ(M, SquareMatrix<3>::Identity());
}

TEST(RegionAdaptive, SlidingWindowForgetsOldTransitions) {
  policies::RegionAdaptiveTransition<3, 2> pol(asymmetric_prior(), 0.5, 0.5);
  for (int l : {0, 0, 0, 1, 2, 2}) pol.observe_region(l);
  // last two transitions: 1->2, 2->2
  SquareMatrix<3> expected_counts = SquareMatrix<3>::Zero();
  expected_counts(1, 2) = 1.0;
  expected_counts(2, 2) = 1.0;
  EXPECT_EQ(pol.counts(), expected_counts);
  SquareMatrix<3> M;
  M << 1, 0, 0, 0, 0, 1, 0, 0, 1;
  EXPECT_EQ(pol.recognised_matrix(), M);
}

TEST(RegionAdaptive, RejectsWeightsThatBreakStochasticity) {
  EXPECT_THROW(policies::RegionAdaptiveTransition<3>(asymmetric_prior(), 0.5, 0.6), std::invalid_argument);
  SquareMatrix<3> bad = asymmetric_prior();
  bad(0, 0) = 0.5;
  EXPECT_THROW(policies::FixedTransition<3>{bad}, std::invalid_argument);
}

TEST(RegionAdaptive, ReducesToTheFixedMatrixWhenRecognisedWeightIsZero) {
  using Proc = models::LinearProcess<2>;
  auto proc = [](double d, double q) {
    Proc p;
    p.F << 1.0, d, 0.0, 1.0;
    p.Q << q, 0.0, 0.0, 1e-4;
    return p;
  };
  auto modes = hana::make_tuple(imm::make_mode(proc(1.0, 0.1)), imm::make_mode(proc(0.0, 0.5)),
                                imm::make_mode(proc(-1.0, 0.2)));
  Gaussian<2> init;
  init.mean << 0.0, 1.0;
  imm::Imm fixed(policies::FixedTransition<3>(asymmetric_prior()), modes, init, Vector<3>(0.2, 0.5, 0.3));
  imm::Imm adaptive(policies::RegionAdaptiveTransition<3>(asymmetric_prior(), 1.0, 0.0), modes, init,
                    Vector<3>(0.2, 0.5, 0.3));
  models::LinearMeasurement<1, 2> meas;
  meas.H << 1.0, 0.0;
  meas.R << 0.3;
  struct Tag {};
  const int labels[] = {0, 0, 1, 2, 2, 1, 0, 0};
  for (int k = 0; k < 8; ++k) {
    adaptive.mixing().observe_region(labels[k]);
    EXPECT_EQ(adaptive.mixing().matrix(), asymmetric_prior());
    ASSERT_TRUE(fixed.mix());
    ASSERT_TRUE(adaptive.mix());
    ASSERT_TRUE(fixed.predict({}, 1.0));
    ASSERT_TRUE(adaptive.predict({}, 1.0));
    fixed.update(Tag{}, meas, Vector<1>(0.7 * k));
    adaptive.update(Tag{}, meas, Vector<1>(0.7 * k));
    fixed.update_mode_probabilities();
    adaptive.update_mode_probabilities();
    EXPECT_EQ(fixed.mode_probabilities(), adaptive.mode_probabilities());
    EXPECT_EQ(fixed.combined().mean, adaptive.combined().mean);
  }
}

TEST(PosteriorPull, PullsRowsTowardThePosterior) {
  policies::PosteriorPull<3, policies::FixedTransition<3>> pol(policies::FixedTransition<3>(asymmetric_prior()), 0.25);
  EXPECT_EQ(pol.matrix(), asymmetric_prior());  // no posterior yet
  pol.observe_posterior(Vector<3>(0.0, 0.0, 2.0));  // normalised to (0, 0, 1)
  const SquareMatrix<3> P = pol.matrix();
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(P.row(i).sum(), 1.0, 1e-15);
    EXPECT_NEAR(P(i, 2), 0.75 * asymmetric_prior()(i, 2) + 0.25, 1e-15);
    EXPECT_NEAR(P(i, 0), 0.75 * asymmetric_prior()(i, 0), 1e-15);
  }
  pol.observe_posterior(Vector<3>(std::numeric_limits<double>::quiet_NaN(), 0.0, 1.0));
  EXPECT_EQ(pol.matrix(), asymmetric_prior());
}

// ---- federated filter -------------------------------------------------------------------
Eigen::Matrix3d random_spd(int seed) {
  std::srand(static_cast<unsigned>(seed));
  const Eigen::Matrix3d A = Eigen::Matrix3d::Random();
  return A * A.transpose() + 0.5 * Eigen::Matrix3d::Identity();
}

// x+ = x with process noise q I.
models::LinearProcess<3> identity_process(double q) {
  models::LinearProcess<3> lin;
  lin.Q = q * SquareMatrix<3>::Identity();
  return lin;
}

TEST(Federated, FusionMatchesInformationForm) {
  std::array<Gaussian<3>, 3> locals;
  for (int i = 0; i < 3; ++i) {
    locals[i].cov = random_spd(i + 1);
    locals[i].mean = Eigen::Vector3d(1.0 * i, -0.5 * i, 2.0 + i);
  }
  Gaussian<3> g;
  models::LinearProcess<3> lin;  // plain vector: no angle handling
  ASSERT_TRUE(fkf::fuse(lin, locals, g));
  Eigen::MatrixXd info = Eigen::MatrixXd::Zero(3, 3);
  Eigen::VectorXd istate = Eigen::VectorXd::Zero(3);
  for (const auto& b : locals) {
    const Eigen::MatrixXd Pinv = Eigen::MatrixXd(b.cov).inverse();
    info += Pinv;
    istate += Pinv * Eigen::VectorXd(b.mean);
  }
  const Eigen::MatrixXd Pg = info.inverse();
  const Eigen::VectorXd xg = Pg * istate;
  EXPECT_LT((g.cov - Pg).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((g.mean - xg).cwiseAbs().maxCoeff(), 1e-12);

  // Not positive definite: refused, output untouched.
  locals[1].cov(0, 0) = -1.0;
  Gaussian<3> untouched;
  const Status refused = fkf::fuse(lin, locals, untouched);
  EXPECT_EQ(refused.outcome, Outcome::numerical_failure);
  EXPECT_EQ(refused.problem, Problem::covariance_not_positive_definite);
  EXPECT_EQ(untouched.mean, Vector<3>::Zero());
}

TEST(Federated, OperationsReportThroughStatus) {
  const models::LinearProcess<3> lin = identity_process(0.1);
  Gaussian<3> init;
  init.cov = random_spd(5);
  fkf::FederatedFilter<models::LinearProcess<3>, 2> f(lin, init, {0.5, 0.5});
  models::LinearMeasurement<1, 3> meas;
  meas.H << 1.0, 0.0, 0.0;
  // A local filter that does not exist has its own problem, not the measurement's.
  for (int bad : {-1, 2}) {
    const Status s = f.update(bad, meas, Vector<1>(0.3));
    EXPECT_EQ(s.outcome, Outcome::invalid_input) << bad;
    EXPECT_EQ(s.problem, Problem::local_filter_index_out_of_range) << bad;
  }
  EXPECT_EQ(f.local(0).mean, init.mean);
  EXPECT_EQ(f.local(1).mean, init.mean);
  ASSERT_TRUE(f.update(1, meas, Vector<1>(0.3)));
  EXPECT_NE(f.local(1).mean, init.mean);
  ASSERT_TRUE(f.fuse_and_reset());

  // Locals that are not positive definite (the constructor takes the initial belief as it
  // is): the fusion is refused with a status and the global estimate is kept.
  Gaussian<3> indefinite = init;
  indefinite.cov(0, 0) = -1.0;
  fkf::FederatedFilter<models::LinearProcess<3>, 2> g(lin, indefinite, {0.5, 0.5});
  const Status refused = g.fuse_and_reset();
  EXPECT_EQ(refused.outcome, Outcome::numerical_failure);
  EXPECT_EQ(refused.problem, Problem::covariance_not_positive_definite);
  EXPECT_EQ(g.global().cov, indefinite.cov);
}

TEST(Federated, ResetSharesInformationByBeta) {
  const models::LinearProcess<3> lin = identity_process(0.1);
  Gaussian<3> init;
  init.cov = random_spd(4);
  fkf::FederatedFilter<models::LinearProcess<3>, 2> f(lin, init, {0.25, 0.75});
  EXPECT_LT((f.local(0).cov - init.cov / 0.25).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((f.local(1).cov - init.cov / 0.75).cwiseAbs().maxCoeff(), 1e-15);
  // The fused covariance of the reset locals is the global one again: (sum beta_i P^-1)^-1 = P.
  ASSERT_TRUE(f.predict({}, 1.0).accepted());
  // Each local got Q / beta_i: P_i = P/beta_i + Q/beta_i, so the fusion gives P + Q exactly.
  ASSERT_TRUE(f.fuse_and_reset());
  EXPECT_LT((f.global().cov - (init.cov + lin.Q)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_THROW((fkf::FederatedFilter<models::LinearProcess<3>, 2>(lin, init, {0.5, 0.6})), std::invalid_argument);
}

TEST(Federated, HeadingsAcrossTheWrapFuseToTheWrap) {
  models::PlanarImuModel model;
  using L = models::PlanarLayout;
  std::array<Gaussian<8>, 2> locals;
  for (auto& b : locals) b.cov = SquareMatrix<8>::Identity() * 0.01;
  locals[0].mean(L::offset<"psi">()) = std::numbers::pi - 0.1;
  locals[1].mean(L::offset<"psi">()) = -std::numbers::pi + 0.1;
  Gaussian<8> g;
  ASSERT_TRUE(fkf::fuse(model, locals, g));
  EXPECT_NEAR(std::abs(g.mean(L::offset<"psi">())), std::numbers::pi, 1e-12);
}

}  // namespace

// The IMM's newcomer-facing API against the textbook, written out plainly here (Bar-Shalom,
// Li, Kirubarajan ch. 11.6.6): the mixing weights mu_{i|j} = p_ij mu_i / c_j, the two priors
// of the combined estimate (weighted with c_j = sum_i p_ij mu_i, or with the last mu_i), the
// status of a cycle that was not closed, and cycle() as the split steps in one call.
#include <gtest/gtest.h>

#include <cstring>

#include "ctxfuse/filters/imm.hpp"
#include "ctxfuse/models/linear.hpp"
#include "ctxfuse/policies/mixing.hpp"

namespace {
using namespace ctxfuse;
namespace hana = boost::hana;
using Proc = models::LinearProcess<2>;
using Meas = models::LinearMeasurement<1, 2>;
using imm::PriorWeights;

struct ApiTag {};

SquareMatrix<3> transition() {
  SquareMatrix<3> T;
  T << 0.90, 0.07, 0.03,
       0.15, 0.80, 0.05,
       0.02, 0.18, 0.80;
  return T;
}

Proc proc(double drift, double q) {
  Proc p;
  p.F << 1.0, drift, 0.0, 1.0;
  p.Q << q, 0.0, 0.0, 0.01;
  return p;
}

Meas position_meas() {
  Meas m;
  m.H << 1.0, 0.0;
  m.R << 0.25;
  return m;
}

auto make_imm(PriorWeights prior = PriorWeights::previous_posterior) {
  Gaussian<2> init;
  init.mean << 0.0, 1.0;
  init.cov << 1.0, 0.2, 0.2, 0.5;
  imm::ImmOptions<3> o;
  o.probability_floor = 0.0;  // the textbook has none
  o.prior_weights = prior;
  auto f = imm::Imm(policies::FixedTransition<3>(transition()),
                    hana::make_tuple(imm::make_mode(proc(1.0, 0.01)), imm::make_mode(proc(0.0, 1.0)),
                                     imm::make_mode(proc(-1.0, 0.3))),
                    init, Vector<3>(0.5, 0.3, 0.2), o);
  // Distinct mode beliefs, so that mixing and combining are not trivial.
  f.template mode_belief<1>().mean << 0.5, 0.7;
  f.template mode_belief<1>().cov << 2.0, -0.3, -0.3, 1.0;
  f.template mode_belief<2>().mean << -0.4, 1.5;
  f.template mode_belief<2>().cov << 0.7, 0.1, 0.1, 0.9;
  return f;
}

using Filter = decltype(make_imm());

// The mode beliefs and their weighted moment match, by the textbook sums.
struct Moments {
  Vector<2> x = Vector<2>::Zero();
  SquareMatrix<2> P = SquareMatrix<2>::Zero();
};
Moments textbook_combination(const Filter& f, const Vector<3>& weight) {
  const Vector<2> xs[3] = {f.mode_belief<0>().mean, f.mode_belief<1>().mean, f.mode_belief<2>().mean};
  const SquareMatrix<2> Ps[3] = {f.mode_belief<0>().cov, f.mode_belief<1>().cov, f.mode_belief<2>().cov};
  Moments m;
  for (int j = 0; j < 3; ++j) m.x += weight(j) * xs[j];
  for (int j = 0; j < 3; ++j) {
    const Vector<2> d = xs[j] - m.x;
    m.P += weight(j) * (Ps[j] + d * d.transpose());
  }
  return m;
}

void expect_belief_near(const Gaussian<2>& b, const Moments& m, double tol) {
  EXPECT_LT((b.mean - m.x).cwiseAbs().maxCoeff(), tol);
  EXPECT_LT((b.cov - m.P).cwiseAbs().maxCoeff(), tol);
}

TEST(ImmApi, MixingWeightsAreTheTextbookFormula) {
  auto f = make_imm();
  // Before any mixing every mode is its own.
  EXPECT_EQ(f.mixing_weights(), (SquareMatrix<3>::Identity()));
  const Vector<3> mu = f.mode_probabilities();
  const SquareMatrix<3> T = transition();
  ASSERT_TRUE(f.mix());
  for (int j = 0; j < 3; ++j) {
    const double c = T(0, j) * mu(0) + T(1, j) * mu(1) + T(2, j) * mu(2);
    EXPECT_NEAR(f.predicted_probabilities()(j), c, 1e-15);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(f.mixing_weights()(i, j), T(i, j) * mu(i) / c, 1e-15) << i << j;
  }
  // By hand for one entry: mu_{1|0} = 0.15 * 0.3 / (0.9 * 0.5 + 0.15 * 0.3 + 0.02 * 0.2).
  EXPECT_NEAR(f.mixing_weights()(1, 0), 0.045 / 0.499, 1e-15);
  // The weights are what mix() used: mode 0's mixed mean is sum_i mu_{i|0} x_i.
  auto before = make_imm();
  const Vector<2> x0 = f.mixing_weights()(0, 0) * before.mode_belief<0>().mean +
                       f.mixing_weights()(1, 0) * before.mode_belief<1>().mean +
                       f.mixing_weights()(2, 0) * before.mode_belief<2>().mean;
  EXPECT_LT((f.mode_belief<0>().mean - x0).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(ImmApi, BothPriorsMatchTheTextbook) {
  for (const PriorWeights option : {PriorWeights::previous_posterior, PriorWeights::predicted}) {
    auto f = make_imm(option);
    const Vector<3> mu = f.mode_probabilities();
    const SquareMatrix<3> T = transition();
    Vector<3> c;
    for (int j = 0; j < 3; ++j) c(j) = T(0, j) * mu(0) + T(1, j) * mu(1) + T(2, j) * mu(2);
    const Moments posterior_before_mix = textbook_combination(f, mu);

    ASSERT_TRUE(f.mix());
    // Right after mixing, the c-weighted prior is the estimate before mixing (the mixing only
    // redistributes it among the modes); the mu-weighted one is not.
    expect_belief_near(f.combined(PriorWeights::predicted), posterior_before_mix, 1e-14);
    const Moments stale = textbook_combination(f, mu);
    EXPECT_GT((stale.x - posterior_before_mix.x).cwiseAbs().maxCoeff(), 1e-6);

    ASSERT_TRUE(f.predict({}, 1.0));
    // x(k|k-1) = sum_j c_j x_j(k|k-1), P(k|k-1) = sum_j c_j (P_j + d_j d_j'): the textbook prior.
    expect_belief_near(f.combined(PriorWeights::predicted), textbook_combination(f, c), 1e-13);
    // Today's: the same sum with the last closed cycle's mu_j.
    expect_belief_near(f.combined(PriorWeights::previous_posterior), textbook_combination(f, mu), 1e-13);
    // combined() follows the option.
    expect_belief_near(f.combined(), textbook_combination(f, option == PriorWeights::predicted ? c : mu), 1e-13);
    EXPECT_EQ(f.combination_weights(), option == PriorWeights::predicted ? c : mu);

    // Once the cycle is closed both are the posterior.
    ASSERT_EQ(f.update(ApiTag{}, position_meas(), Vector<1>(1.3)).accepted_count, 3);
    f.update_mode_probabilities();
    const Moments post = textbook_combination(f, f.mode_probabilities());
    expect_belief_near(f.combined(PriorWeights::predicted), post, 1e-13);
    expect_belief_near(f.combined(PriorWeights::previous_posterior), post, 1e-13);
  }
}

// Mean and covariance bit for bit. Not memcmp of the whole struct: with AVX (x86-64-v3) Eigen
// aligns the 2x2 covariance to 32 bytes, leaving 16 bytes of padding after the mean whose
// contents a copy need not preserve.
template <class B>
bool same_bytes(const B& a, const B& b) {
  return std::memcmp(a.mean.data(), b.mean.data(), sizeof(a.mean)) == 0 &&
         std::memcmp(a.cov.data(), b.cov.data(), sizeof(a.cov)) == 0;
}

TEST(ImmApi, MixingAnOpenCycleIsRefusedAndChangesNothing) {
  auto f = make_imm();
  ASSERT_TRUE(f.mix());
  EXPECT_TRUE(f.cycle_open());
  ASSERT_TRUE(f.predict({}, 1.0));
  ASSERT_EQ(f.update(ApiTag{}, position_meas(), Vector<1>(1.3)).accepted_count, 3);
  const Vector<3> mu = f.mode_probabilities(), c = f.predicted_probabilities(), ll = f.cycle_log_likelihood();
  const SquareMatrix<3> w = f.mixing_weights();
  const auto b0 = f.mode_belief<0>();
  const auto b1 = f.mode_belief<1>();
  const auto b2 = f.mode_belief<2>();

  // The close forgotten: mixing again would have kept mu at its initial value forever.
  const Status s = f.mix();
  EXPECT_EQ(s.outcome, Outcome::invalid_input);
  EXPECT_EQ(s.problem, Problem::imm_cycle_not_closed);
  EXPECT_TRUE(f.cycle_open());
  EXPECT_EQ(f.mode_probabilities(), mu);
  EXPECT_EQ(f.predicted_probabilities(), c);
  EXPECT_EQ(f.cycle_log_likelihood(), ll);
  EXPECT_EQ(f.mixing_weights(), w);
  EXPECT_TRUE(same_bytes(f.mode_belief<0>(), b0));
  EXPECT_TRUE(same_bytes(f.mode_belief<1>(), b1));
  EXPECT_TRUE(same_bytes(f.mode_belief<2>(), b2));

  f.update_mode_probabilities();
  EXPECT_FALSE(f.cycle_open());
  EXPECT_NE(f.mode_probabilities(), mu);
  EXPECT_TRUE(f.mix());
}

// A policy whose matrix a caller broke after construction (FixedTransition would have thrown).
struct BrokenMixing {
  SquareMatrix<3> P = transition();
  SquareMatrix<3> matrix() const { return P; }
};

TEST(ImmApi, BadTransitionMatrixIsAStatus) {
  Gaussian<2> init;
  init.cov.setIdentity();
  auto f = imm::Imm(BrokenMixing{}, hana::make_tuple(imm::make_mode(proc(1.0, 0.1)), imm::make_mode(proc(0.0, 0.1)),
                                                     imm::make_mode(proc(-1.0, 0.1))),
                    init, Vector<3>::Constant(1.0 / 3.0));
  f.mixing().P(0, 0) = 0.5;  // row 0 sums to 0.6
  Status s = f.mix();
  EXPECT_EQ(s.outcome, Outcome::invalid_input);
  EXPECT_EQ(s.problem, Problem::transition_matrix_not_stochastic);
  EXPECT_FALSE(f.cycle_open());
  f.mixing().P(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(f.mix().problem, Problem::transition_matrix_not_stochastic);
  f.mixing().P = transition();
  EXPECT_TRUE(f.mix());
}

TEST(ImmApi, CycleIsTheSplitStepsInOneCall) {
  auto split = make_imm();
  auto one = make_imm();
  Meas velocity;
  velocity.H << 0.0, 1.0;
  velocity.R << 0.5;
  const double zs[] = {1.3, 2.1, 2.6, 4.9, 4.0};
  for (double z : zs) {
    ASSERT_TRUE(split.mix());
    ASSERT_TRUE(split.predict({}, 1.0));
    const auto a = split.update(ApiTag{}, position_meas(), Vector<1>(z));
    const auto b = split.update(ApiTag{}, velocity, Vector<1>(0.8), 0b011u);
    split.update_mode_probabilities();

    const auto r = one.cycle({}, 1.0, imm::observe(ApiTag{}, position_meas(), Vector<1>(z)),
                             imm::observe(ApiTag{}, velocity, Vector<1>(0.8), 0b011u));
    ASSERT_TRUE(r.status());
    EXPECT_FALSE(one.cycle_open());
    EXPECT_EQ(r.updates[0].accepted_count, a.accepted_count);
    EXPECT_EQ(r.updates[1].taken, b.taken);
    EXPECT_EQ(one.mode_probabilities(), split.mode_probabilities());
    EXPECT_EQ(one.mode_belief<0>().mean, split.mode_belief<0>().mean);
    EXPECT_EQ(one.mode_belief<2>().cov, split.mode_belief<2>().cov);
  }
}

TEST(ImmApi, CycleReportsARefusedStepAndStaysUsable) {
  auto f = make_imm();
  const Vector<3> mu0 = f.mode_probabilities();
  const Vector<3> c = transition().transpose() * mu0;  // c_j = sum_i p_ij mu_i
  // A bad time step: no mode predicts, the measurement is not applied, the cycle is closed
  // with mu = c (the probabilities of the mixed beliefs).
  const auto r = f.cycle({}, -1.0, imm::observe(ApiTag{}, position_meas(), Vector<1>(1.0)));
  EXPECT_TRUE(r.mix);
  EXPECT_EQ(r.status().problem, Problem::non_positive_dt);
  EXPECT_EQ(r.updates[0].taken_count, 0);
  EXPECT_FALSE(f.cycle_open());
  EXPECT_LT((f.mode_probabilities() - c).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_GT((mu0 - c).cwiseAbs().maxCoeff(), 1e-3);  // so the line above tells them apart
  EXPECT_TRUE(f.cycle({}, 1.0, imm::observe(ApiTag{}, position_meas(), Vector<1>(1.0))).status());

  // An open cycle left by the split steps: cycle() refuses at its mix and changes nothing.
  ASSERT_TRUE(f.mix());
  const Vector<3> mu = f.mode_probabilities();
  const auto refused = f.cycle({}, 1.0, imm::observe(ApiTag{}, position_meas(), Vector<1>(2.0)));
  EXPECT_EQ(refused.status().problem, Problem::imm_cycle_not_closed);
  EXPECT_EQ(f.mode_probabilities(), mu);
  EXPECT_TRUE(f.cycle_open());
}

}  // namespace

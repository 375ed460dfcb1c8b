// Dempster-Shafer combination, consistency model and decision policies against hand values.
#include <gtest/gtest.h>

#include <ctxfuse/classify/consistency.hpp>
#include <ctxfuse/classify/dempster_shafer.hpp>

#include <array>
#include <cmath>
#include <vector>

namespace {

using namespace ctxfuse::classify;
using ctxfuse::Problem;

TEST(DempsterShafer, PaperFormTwoSources) {
  // p1 = 0.9, p2 = 0.7: K = 0.63 + 0.03 = 0.66, R = 0.63 / 0.66
  const auto r = combine_probabilities(0.9, 0.7);
  EXPECT_TRUE(r.status.accepted());
  EXPECT_NEAR(r.nlos_belief(), 0.63 / 0.66, 1e-15);
  EXPECT_NEAR(r.mass.los, 0.03 / 0.66, 1e-15);
  EXPECT_NEAR(r.conflict, 0.34, 1e-15);
  EXPECT_EQ(r.mass.either, 0.0);
  // Agreeing weak evidence reinforces: 0.6, 0.6 -> 0.36 / (0.36 + 0.16)
  EXPECT_NEAR(combine_probabilities(0.6, 0.6).nlos_belief(), 0.36 / 0.52, 1e-15);
  // A 0.5 source is neutral.
  EXPECT_NEAR(combine_probabilities(0.5, 0.83).nlos_belief(), 0.83, 1e-15);
}

TEST(DempsterShafer, ThreeSourcesClosedForm) {
  const std::array<BinaryMass, 3> s{BinaryMass::from_probability(0.8), BinaryMass::from_probability(0.7),
                                    BinaryMass::from_probability(0.4)};
  const auto r = combine(std::span<const BinaryMass>(s));
  const double nlos = 0.8 * 0.7 * 0.4, los = 0.2 * 0.3 * 0.6;
  EXPECT_NEAR(r.nlos_belief(), nlos / (nlos + los), 1e-15);
  EXPECT_NEAR(r.conflict, 1.0 - (nlos + los), 1e-15);
}

TEST(DempsterShafer, MassOnWholeFrame) {
  // a: N 0.6, L 0.1, Theta 0.3; b: N 0.2, L 0.5, Theta 0.3
  // N: .12 + .18 + .06 = .36; L: .05 + .03 + .15 = .23; Theta: .09; conflict .30 + .02 = .32
  const auto r = combine(BinaryMass{0.6, 0.1, 0.3}, BinaryMass{0.2, 0.5, 0.3});
  EXPECT_NEAR(r.conflict, 0.32, 1e-15);
  EXPECT_NEAR(r.mass.nlos, 0.36 / 0.68, 1e-15);
  EXPECT_NEAR(r.mass.los, 0.23 / 0.68, 1e-15);
  EXPECT_NEAR(r.mass.either, 0.09 / 0.68, 1e-15);
  EXPECT_NEAR(r.mass.plausibility_nlos(), 0.45 / 0.68, 1e-15);
  // A vacuous source changes nothing.
  const auto v = combine(BinaryMass{0.6, 0.1, 0.3}, BinaryMass{0.0, 0.0, 1.0});
  EXPECT_NEAR(v.mass.nlos, 0.6, 1e-15);
  EXPECT_EQ(v.conflict, 0.0);
}

TEST(DempsterShafer, TotalConflictIsReportedNotDivided) {
  const auto r = combine_probabilities(1.0, 0.0);
  EXPECT_EQ(r.status.problem, Problem::total_conflict);
  EXPECT_EQ(r.conflict, 1.0);
  EXPECT_TRUE(std::isfinite(r.mass.nlos));
  EXPECT_EQ(r.mass.either, 1.0);
  const std::array<BinaryMass, 3> s{BinaryMass::from_probability(0.7), BinaryMass::from_probability(1.0),
                                    BinaryMass::from_probability(0.0)};
  EXPECT_EQ(combine(std::span<const BinaryMass>(s)).status.problem, Problem::total_conflict);
}

TEST(DempsterShafer, InvalidMassesAreRejected) {
  EXPECT_EQ(combine_probabilities(std::nan(""), 0.5).status.problem, Problem::invalid_mass);
  EXPECT_EQ(combine_probabilities(1.5, 0.5).status.problem, Problem::invalid_mass);
  EXPECT_EQ(combine(BinaryMass{0.5, 0.5, 0.5}, BinaryMass{0.5, 0.5, 0.0}).status.problem, Problem::invalid_mass);
}

TEST(ConsistencyModel, PaperStepsAtOneTwoThreeSigma) {
  const ConsistencyModel m;  // sigma 0.1
  EXPECT_EQ(m.nlos_probability(-0.5), 0.35);
  EXPECT_EQ(m.nlos_probability(0.1), 0.35);   // e <= sigma
  EXPECT_EQ(m.nlos_probability(0.15), 0.55);  // sigma < e <= 2 sigma
  EXPECT_EQ(m.nlos_probability(0.25), 0.70);
  EXPECT_EQ(m.nlos_probability(0.31), 0.90);
  EXPECT_EQ(m.nlos_probability(1e9), 0.90);
  EXPECT_TRUE(std::isnan(m.nlos_probability(std::nan(""))));
  // Range shrank 0.5 m while the car moved 0.2 m: e = 0.3 -> third bin.
  EXPECT_NEAR(ConsistencyModel::consistency_error(-0.5, 0.2), 0.3, 1e-15);
  EXPECT_EQ(m.nlos_probability(-0.5, 0.2), 0.70);
  EXPECT_TRUE(m.check().ok());
}

TEST(ConsistencyModel, CustomParametersAndValidation) {
  ConsistencyModel m;
  m.sigma_uwb = 0.2;
  m.sigma_multiples = {0.5, 1.0, 4.0};
  m.probabilities = {0.1, 0.2, 0.3, 0.4};
  EXPECT_EQ(m.nlos_probability(0.1), 0.1);
  EXPECT_EQ(m.nlos_probability(0.15), 0.2);
  EXPECT_EQ(m.nlos_probability(0.5), 0.3);
  EXPECT_EQ(m.nlos_probability(0.81), 0.4);
  m.sigma_multiples = {1.0, 1.0, 2.0};
  EXPECT_FALSE(m.check().ok());
  m = ConsistencyModel{};
  m.sigma_uwb = 0.0;
  EXPECT_FALSE(m.check().ok());
  m = ConsistencyModel{};
  m.probabilities[2] = 1.1;
  EXPECT_FALSE(m.check().ok());
}

TEST(NlosPolicies, DecisionAndAttachRules) {
  const NlosDecisionRule rule;
  EXPECT_FALSE(rule(0.8));
  EXPECT_TRUE(rule(0.8000001));
  // SVM p1 = 0.9 with consistency p2 = 0.7 -> R = 0.9545 -> NLOS
  EXPECT_TRUE(rule(combine_probabilities(0.9, 0.7).nlos_belief()));
  // p1 = 0.6, p2 = 0.7 -> R = 0.42 / 0.54 = 0.778 -> LOS
  EXPECT_FALSE(rule(combine_probabilities(0.6, 0.7).nlos_belief()));

  const FactorAttachPolicy attach;
  EXPECT_TRUE(attach.attach(4, 0, 0.0));     // all LOS
  EXPECT_TRUE(attach.attach(4, 1, 0.71));    // 1 of 4 NLOS and R > 0.7
  EXPECT_FALSE(attach.attach(4, 1, 0.7));    // R not above 0.7
  EXPECT_FALSE(attach.attach(4, 2, 0.99));   // half NLOS is not "fewer than half"
  EXPECT_FALSE(attach.attach(3, 2, 0.99));
  EXPECT_TRUE(attach.attach(5, 2, 0.75));
  EXPECT_FALSE(attach.attach(0, 0, 1.0));    // no ranges: nothing to attach
  EXPECT_FALSE(attach.attach(4, 5, 1.0));
}

}  // namespace

// Weighted SVM+HMM vote and region transition matrix against hand-computed values.
#include <gtest/gtest.h>

#include <ctxfuse/classify/joint.hpp>
#include <ctxfuse/classify/region_transition.hpp>

#include <array>
#include <vector>

namespace {

using Vote = ctxfuse::classify::WeightedVote<3, 2>;

// P_S = (0.96, 0.90, 0.99), P_H = (0.88, 0.95, 0.81):
// w_s = (0.96/1.84, 0.90/1.85, 0.99/1.80) = (0.521739, 0.486486, 0.55)
// w_h = (0.88/1.84, 0.95/1.85, 0.81/1.80) = (0.478261, 0.513514, 0.45)
const Vote kVote = Vote::from_accuracies({{{0.96, 0.90, 0.99}, {0.88, 0.95, 0.81}}});

TEST(WeightedVote, WeightsAreNormalisedPerRegion) {
  EXPECT_NEAR(kVote.weights[0][0], 0.96 / 1.84, 1e-15);
  EXPECT_NEAR(kVote.weights[1][1], 0.95 / 1.85, 1e-15);
  EXPECT_NEAR(kVote.weights[0][2], 0.55, 1e-15);
  EXPECT_NEAR(kVote.weights[1][2], 0.45, 1e-15);
}

TEST(WeightedVote, AgreementScoresOne) {
  const auto d = kVote.decide({1, 1});
  EXPECT_EQ(d.region, 1);
  EXPECT_NEAR(d.scores[1], 1.0, 1e-15);
  EXPECT_EQ(d.scores[0], 0.0);
}

TEST(WeightedVote, DisagreementGoesToTheHeavierWeight) {
  // SVM says 0 (w_s,0 = 0.5217), HMM says 1 (w_h,1 = 0.5135): SVM wins.
  auto d = kVote.decide({0, 1});
  EXPECT_EQ(d.region, 0);
  EXPECT_NEAR(d.scores[0], 0.96 / 1.84, 1e-15);
  EXPECT_NEAR(d.scores[1], 0.95 / 1.85, 1e-15);
  // SVM says 1 (0.4865), HMM says 0 (0.4783): SVM wins again.
  EXPECT_EQ(kVote({1, 0}), 1);
  // SVM says 2 (0.55), HMM says 1 (0.5135): 2.
  EXPECT_EQ(kVote({2, 1}), 2);
  // SVM says 1 (0.4865), HMM says 2 (0.45): 1.
  EXPECT_EQ(kVote({1, 2}), 1);
  // Make the HMM clearly better on region 2: SVM says 0 (0.9/1.5 = 0.6)... HMM says 2 (0.9/1.2=0.75)
  const Vote v = Vote::from_accuracies({{{0.9, 0.9, 0.3}, {0.6, 0.9, 0.9}}});
  EXPECT_EQ(v({0, 2}), 2);
  EXPECT_NEAR(v.decide({0, 2}).scores[0], 0.6, 1e-15);
  EXPECT_NEAR(v.decide({0, 2}).scores[2], 0.75, 1e-15);
}

TEST(WeightedVote, TiesGoToTheFirstClassifier) {
  const Vote equal = Vote::from_accuracies({{{0.9, 0.9, 0.9}, {0.9, 0.9, 0.9}}});
  EXPECT_EQ(equal({0, 2}), 0);
  EXPECT_EQ(equal({2, 0}), 2);
}

TEST(WeightedVote, InvalidVotesAndAccuraciesAreHandled) {
  EXPECT_EQ(kVote({-1, 2}), 2);
  EXPECT_EQ(kVote({-1, 7}), -1);
  EXPECT_THROW(Vote::from_accuracies({{{1.2, 0.9, 0.9}, {0.9, 0.9, 0.9}}}), std::invalid_argument);
  const Vote zero = Vote::from_accuracies({{{0.0, 0.9, 0.9}, {0.0, 0.9, 0.9}}});
  EXPECT_EQ(zero.weights[0][0], 0.5);
}

TEST(PerRegionAccuracy, CountsPerTrueRegion) {
  const std::vector<int> truth{0, 0, 0, 1, 1, 2, 2, 2, 2};
  const std::vector<int> pred{0, 1, 0, 1, 0, 2, 2, 2, 0};
  const auto acc = ctxfuse::classify::per_region_accuracy<3>(truth, pred);
  EXPECT_NEAR(acc[0], 2.0 / 3.0, 1e-15);
  EXPECT_NEAR(acc[1], 0.5, 1e-15);
  EXPECT_NEAR(acc[2], 0.75, 1e-15);
}

TEST(RegionTransition, MatrixFromCountsByHand) {
  // 0 0 1 1 1 2 2 0: 0->0, 0->1, 1->1, 1->1, 1->2, 2->2, 2->0
  const std::vector<int> labels{0, 0, 1, 1, 1, 2, 2, 0};
  const auto m = ctxfuse::classify::region_transition_matrix<3>(labels);
  EXPECT_DOUBLE_EQ(m(0, 0), 0.5);
  EXPECT_DOUBLE_EQ(m(0, 1), 0.5);
  EXPECT_DOUBLE_EQ(m(0, 2), 0.0);
  EXPECT_DOUBLE_EQ(m(1, 1), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(m(1, 2), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(m(2, 0), 0.5);
  EXPECT_DOUBLE_EQ(m(2, 2), 0.5);
}

TEST(RegionTransition, EmptyRowsFollowThePolicy) {
  const std::vector<int> labels{0, 0, 1, 1};  // region 2 never seen, region 1 never left
  const auto id = ctxfuse::classify::region_transition_matrix<3>(labels);
  EXPECT_DOUBLE_EQ(id(1, 1), 1.0);
  EXPECT_DOUBLE_EQ(id(2, 2), 1.0);
  EXPECT_DOUBLE_EQ(id(2, 0), 0.0);
  const auto uni =
      ctxfuse::classify::region_transition_matrix<3, ctxfuse::classify::UniformForEmptyRows>(labels);
  EXPECT_DOUBLE_EQ(uni(2, 0), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(uni(2, 2), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(uni(0, 1), 0.5);
}

TEST(RegionTransition, UnknownLabelsBreakTheChain) {
  ctxfuse::classify::RegionTransitionCounter<3> c;
  for (int l : {0, 0, -1, 2, 2, 9, 1}) c.add(l);
  EXPECT_DOUBLE_EQ(c.counts.sum(), 2.0);  // only 0->0 and 2->2
  EXPECT_DOUBLE_EQ(c.counts(0, 0), 1.0);
  EXPECT_DOUBLE_EQ(c.counts(2, 2), 1.0);
}

TEST(RegionTransition, BlendIsConvexCombination) {
  Eigen::Matrix2d p, m;
  p << 0.9, 0.1, 0.2, 0.8;
  m << 0.5, 0.5, 0.0, 1.0;
  const auto b = ctxfuse::classify::blend_transition<2>(p, m, 0.25);
  EXPECT_DOUBLE_EQ(b(0, 0), 0.25 * 0.9 + 0.75 * 0.5);
  EXPECT_DOUBLE_EQ(b(1, 0), 0.05);
}

}  // namespace

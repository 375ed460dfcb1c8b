// Validation that respects sequences: contiguous blocks and whole groups never on both sides
// of a fold, the fold placement worked by hand, balanced accuracy and macro-F1 against hand
// computations, inverse-frequency weights, class weights moving a linear SVM's boundary as the
// Bayes rule says, a cross-validation that can tell grouped from shuffled folds, and the PSO
// search on a subsample reporting every iteration.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "ctxfuse/classify/svm_train.hpp"

namespace {

using namespace ctxfuse::classify;

// For every fold: the groups (or rows) of its test part appear in no training row.
void expect_disjoint(const std::vector<int>& fold, const std::vector<int>& group) {
  for (int f = 0; f < fold_count(fold); ++f) {
    std::set<int> test, train;
    for (std::size_t i = 0; i < fold.size(); ++i) (fold[i] == f ? test : train).insert(group[i]);
    EXPECT_FALSE(test.empty()) << "fold " << f;
    for (int g : test) EXPECT_EQ(train.count(g), 0u) << "group " << g << " on both sides of fold " << f;
  }
}

TEST(SvmFolds, BlocksAreContiguousAndEven) {
  const auto fold = block_folds(103, 5);
  ASSERT_EQ(fold.size(), 103u);
  for (std::size_t i = 1; i < fold.size(); ++i) EXPECT_TRUE(fold[i] == fold[i - 1] || fold[i] == fold[i - 1] + 1) << i;
  std::vector<int> size(5, 0);
  for (int f : fold) ++size[static_cast<std::size_t>(f)];
  for (int s : size) EXPECT_TRUE(s == 20 || s == 21) << s;  // 103 = 3 x 21 + 2 x 20
  // No row is on both sides of a fold (each row its own group).
  std::vector<int> row(103);
  for (int i = 0; i < 103; ++i) row[static_cast<std::size_t>(i)] = i;
  expect_disjoint(fold, row);
  EXPECT_THROW(block_folds(3, 5), std::invalid_argument);
}

TEST(SvmFolds, GroupsStayWholeLeaveOneOutAndBalanced) {
  // Groups 7 (5 rows), 3 (3), 9 (3), 4 (2), 8 (1), interleaved.
  const std::vector<int> g{7, 3, 7, 9, 4, 7, 3, 9, 7, 4, 3, 9, 8, 7};
  const auto logo = group_folds(g, 0);
  expect_disjoint(logo, g);
  EXPECT_EQ(fold_count(logo), 5);
  EXPECT_EQ(logo[0], 0);  // first appearance order: 7, 3, 9, 4, 8
  EXPECT_EQ(logo[1], 1);
  EXPECT_EQ(logo[12], 4);
  EXPECT_EQ(group_folds(g, 5), logo);  // k >= groups is leave-one-group-out too
  // Two folds, by hand, largest group first into the lighter fold (loads in brackets):
  // 7 -> 0 [5, 0]; 3 -> 1 [5, 3]; 9 -> 1 [5, 6]; 4 -> 0 [7, 6]; 8 -> 1 [7, 7].
  const auto two = group_folds(g, 2);
  expect_disjoint(two, g);
  const std::map<int, int> expected{{7, 0}, {3, 1}, {9, 1}, {4, 0}, {8, 1}};
  for (std::size_t i = 0; i < g.size(); ++i) EXPECT_EQ(two[i], expected.at(g[i])) << "group " << g[i];
  EXPECT_THROW(group_folds(std::vector<int>{1, 1, 1}), std::invalid_argument);
}

TEST(SvmFolds, BalancedAccuracyAndMacroF1ByHand) {
  // truth 0: 8 samples (6 right, 2 as 1); truth 1: 2 samples (1 right, 1 as 0); truth 2: none,
  // but one class-0 sample predicted 2 -> counts: row0 = {5, 2, 1}, row1 = {1, 1, 0}.
  ctxfuse::classify::ConfusionMatrix m(3);
  for (int i = 0; i < 5; ++i) m.add(0, 0);
  m.add(0, 1), m.add(0, 1), m.add(0, 2), m.add(1, 1), m.add(1, 0);
  // recalls: 5/8 and 1/2 (class 2 has no support) -> (0.625 + 0.5) / 2
  EXPECT_DOUBLE_EQ(m.balanced_accuracy(), (0.625 + 0.5) / 2.0);
  // F1 = 2TP / (2TP + FP + FN): class 0: 10 / (10 + 1 + 3); class 1: 2 / (2 + 2 + 1)
  EXPECT_DOUBLE_EQ(m.macro_f1(), (10.0 / 14.0 + 2.0 / 5.0) / 2.0);
  EXPECT_DOUBLE_EQ(m.accuracy(), 0.6);
  // Always answering the majority class: balanced accuracy 1/2, macro-F1 = F1 of the majority / 2.
  ctxfuse::classify::ConfusionMatrix major(2);
  for (int i = 0; i < 9; ++i) major.add(0, 0);
  major.add(1, 0);
  EXPECT_DOUBLE_EQ(major.accuracy(), 0.9);
  EXPECT_DOUBLE_EQ(major.balanced_accuracy(), 0.5);
  EXPECT_DOUBLE_EQ(major.macro_f1(), (18.0 / 19.0) / 2.0);
  EXPECT_TRUE(std::isnan(ctxfuse::classify::ConfusionMatrix(2).balanced_accuracy()));
}

TEST(SvmFolds, InverseFrequencyWeights) {
  const std::vector<int> y{3, 3, 3, 3, 3, 3, 1, 1};
  const auto w = inverse_frequency_weights(y);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(w[0].first, 1);  // ascending labels
  EXPECT_DOUBLE_EQ(w[0].second, 8.0 / (2.0 * 2.0));
  EXPECT_EQ(w[1].first, 3);
  EXPECT_DOUBLE_EQ(w[1].second, 8.0 / (2.0 * 6.0));
}

// 1-D, class 0 ~ N(0, 1) x 900, class 1 ~ N(2, 1) x 100. The Bayes boundary with the priors is
// at 1 + ln(9) / 2 = 2.10; with equal priors (what inverse-frequency weights stand for) at 1.
double boundary(const SvmModel<1>& model) {
  SvmPrediction<8> p;
  double x = -3.0;
  for (; x < 6.0; x += 0.001) {
    EXPECT_TRUE(svm_predict(model, Eigen::Matrix<double, 1, 1>(x), p).accepted());
    if (p.label == 1) break;
  }
  return x;
}

TEST(SvmFolds, ClassWeightsMoveTheBoundaryTowardsTheMajority) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n01(0.0, 1.0);
  SvmFeatures<1> x(1000, 1);
  std::vector<int> y(1000);
  for (int i = 0; i < 1000; ++i) {
    y[static_cast<std::size_t>(i)] = i % 10 == 0 ? 1 : 0;
    x(i, 0) = (y[static_cast<std::size_t>(i)] ? 2.0 : 0.0) + n01(rng);
  }
  SvmTrainOptions o;
  o.kernel = SvmKernel::linear;
  const double plain = boundary(train_svm<1>(x, y, o));
  o.class_weights = inverse_frequency_weights(y);
  const double weighted = boundary(train_svm<1>(x, y, o));
  // Unweighted, the hinge loss favours the majority: the boundary lies beyond the midpoint.
  EXPECT_GT(plain, 1.5);
  // Weighted, it moves to the equal-prior Bayes boundary (1.0) within the sampling spread.
  EXPECT_NEAR(weighted, 1.0, 0.3);
  EXPECT_LT(weighted, plain - 0.5);
}

TEST(SvmFolds, GroupedValidationSeesWhatShuffledFoldsHide) {
  // Six groups, each a tight cluster at 10 g with label g % 2: a neighbour of the same group
  // gives the label away, a neighbouring group gives the wrong one.
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01(0.0, 0.1);
  SvmFeatures<1> x(120, 1);
  std::vector<int> y(120), g(120);
  for (int i = 0; i < 120; ++i) {
    const int grp = i / 20;
    g[static_cast<std::size_t>(i)] = grp;
    y[static_cast<std::size_t>(i)] = grp % 2;
    x(i, 0) = 10.0 * grp + n01(rng);
  }
  SvmTrainOptions o;
  o.gamma = 50.0;  // in standardised units: a memoriser
  o.C = 100.0;
  const auto shuffled = cross_validate_svm<1>(x, y, o, stratified_folds(y, 5, 1), CvScore::balanced_accuracy);
  const auto grouped = cross_validate_svm<1>(x, y, o, group_folds(g), CvScore::balanced_accuracy);
  EXPECT_GT(shuffled.accuracy, 0.95);
  EXPECT_LT(grouped.accuracy, 0.5);
  EXPECT_DOUBLE_EQ(grouped.score, grouped.balanced_accuracy);
  // Blocks of 20 rows are the groups here: the same figure.
  const auto blocked = cross_validate_svm<1>(x, y, o, block_folds(120, 6));
  EXPECT_DOUBLE_EQ(blocked.accuracy, grouped.accuracy);
}

TEST(SvmFolds, PsoOnASubsampleReportsEveryIteration) {
  std::mt19937_64 rng(8);
  std::normal_distribution<double> n01(0.0, 1.0);
  SvmFeatures<1> x(1001, 1);
  std::vector<int> y(1001);
  for (int i = 0; i < 1001; ++i) {
    y[static_cast<std::size_t>(i)] = (i / 50) % 2;  // blocks of 50
    x(i, 0) = 1.5 * y[static_cast<std::size_t>(i)] + n01(rng);
  }
  SvmTuneOptions tune;
  tune.fold_of_sample = block_folds(1001, 4);
  tune.score = CvScore::macro_f1;
  tune.max_search_samples = 200;
  tune.pso = {.swarm_size = 3, .iterations = 2, .seed = 2};
  std::vector<SvmTuneProgress> seen;
  tune.on_progress = [&](const SvmTuneProgress& p) { seen.push_back(p); };
  SvmTrainOptions o;
  o.kernel = SvmKernel::linear;
  const auto r = tune_svm_pso<1>(x, y, o, tune);
  // Every m-th row, m = ceil(1001 / 200) = 6: rows 0, 6, ..., 996, i.e. 167 rows.
  EXPECT_EQ(r.search_samples, 167u);
  EXPECT_EQ(r.evaluations, 3 * (2 + 1));
  ASSERT_EQ(seen.size(), 3u);  // initial swarm + 2 iterations
  for (std::size_t i = 0; i < seen.size(); ++i) {
    EXPECT_EQ(seen[i].iteration, static_cast<int>(i));
    EXPECT_EQ(seen[i].evaluations, 3 * static_cast<int>(i + 1));
    if (i > 0) {
      EXPECT_GE(seen[i].best_score, seen[i - 1].best_score);
      EXPECT_GE(seen[i].elapsed_s, seen[i - 1].elapsed_s);
    }
  }
  EXPECT_DOUBLE_EQ(seen.back().best_score, r.cv_accuracy);
  EXPECT_DOUBLE_EQ(seen.back().C, r.C);
  // The best score is the macro-F1 of a cross-validation on those 167 rows and their folds.
  SvmFeatures<1> xs(167, 1);
  std::vector<int> ys(167), fs(167);
  const auto folds = block_folds(1001, 4);
  for (int k = 0; k < 167; ++k) {
    xs(k, 0) = x(6 * k, 0);
    ys[static_cast<std::size_t>(k)] = y[static_cast<std::size_t>(6 * k)];
    fs[static_cast<std::size_t>(k)] = folds[static_cast<std::size_t>(6 * k)];
  }
  o.C = r.C;
  EXPECT_DOUBLE_EQ(cross_validate_svm<1>(xs, ys, o, fs, CvScore::macro_f1).macro_f1, r.cv_accuracy);
}

}  // namespace

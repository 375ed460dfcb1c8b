// Training through libsvm: standardisation fitted as the textbook formulas say, stratified folds
// balanced and seeded, cross-validation against a brute-force refit, PSO-tuned (C, gamma)
// beating libsvm's defaults where those are clearly wrong, and bad data rejected.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "classify_svm/svm_test_data.hpp"
#include "ctxfuse/classify/svm_train.hpp"

namespace {

using namespace ctxfuse::classify;

TEST(SvmTrain, StandardisationIsFittedMeanAndPopulationStd) {
  const auto data = ctxfuse::test::gaussian_clusters({{10, -200}, {12, -180}}, {1, 0}, 50, {2.0, 30.0}, 4);
  const SvmFeatures<2> x = data.x;
  SvmTrainOptions o;
  const auto model = train_svm<2>(x, data.y, o);
  for (int f = 0; f < 2; ++f) {
    double sum = 0.0, sq = 0.0;
    for (Eigen::Index i = 0; i < x.rows(); ++i) sum += x(i, f);
    const double mean = sum / static_cast<double>(x.rows());
    for (Eigen::Index i = 0; i < x.rows(); ++i) sq += (x(i, f) - mean) * (x(i, f) - mean);
    EXPECT_NEAR(model.input_mean[f], mean, 1e-12 * std::abs(mean));
    EXPECT_NEAR(model.input_std[f], std::sqrt(sq / static_cast<double>(x.rows())), 1e-12);
  }
  // Support vectors are training rows in standardised units.
  for (Eigen::Index s = 0; s < std::min<Eigen::Index>(5, model.num_support_vectors()); ++s) {
    const Eigen::RowVector2d raw = model.support_vectors.row(s).cwiseProduct(model.input_std.transpose()) + model.input_mean.transpose();
    double best = 1e300;
    for (Eigen::Index i = 0; i < x.rows(); ++i) best = std::min(best, (x.row(i) - raw).norm());
    EXPECT_LT(best, 1e-9);
  }
}

TEST(SvmTrain, StratifiedFoldsAreBalancedAndSeeded) {
  std::vector<int> y;
  for (int i = 0; i < 103; ++i) y.push_back(i % 7 == 0 ? 5 : (i % 3 == 0 ? 1 : 2));
  const auto folds = stratified_folds(y, 5, 11);
  std::map<int, std::map<int, int>> count;  // label -> fold -> n
  for (std::size_t i = 0; i < y.size(); ++i) ++count[y[i]][folds[i]];
  for (const auto& [label, per_fold] : count) {
    int lo = 1 << 30, hi = 0;
    for (int f = 0; f < 5; ++f) {
      const int n = per_fold.count(f) ? per_fold.at(f) : 0;
      lo = std::min(lo, n);
      hi = std::max(hi, n);
    }
    EXPECT_LE(hi - lo, 1) << "label " << label;
  }
  EXPECT_EQ(stratified_folds(y, 5, 11), folds);
  EXPECT_NE(stratified_folds(y, 5, 12), folds);
  const auto test = stratified_split(y, 0.3, 3);
  std::map<int, int> total, in_test;
  for (std::size_t i = 0; i < y.size(); ++i) {
    ++total[y[i]];
    in_test[y[i]] += test[i] ? 1 : 0;
  }
  for (const auto& [label, n] : total) EXPECT_EQ(in_test[label], static_cast<int>(std::llround(0.3 * n)));
}

TEST(SvmTrain, CrossValidationEqualsBruteForceRefits) {
  const auto data = ctxfuse::test::gaussian_clusters({{0, 0}, {1.2, 0.4}, {0.3, 1.5}}, {0, 1, 2}, 40, {0.7, 0.7}, 8);
  const SvmFeatures<2> x = data.x;
  SvmTrainOptions o;
  o.C = 4.0;
  const auto cv = cross_validate_svm<2>(x, data.y, o, 4, 9);
  const auto folds = stratified_folds(data.y, 4, 9);
  std::size_t correct = 0;
  for (int f = 0; f < 4; ++f) {
    std::vector<Eigen::Index> train_rows;
    for (std::size_t i = 0; i < folds.size(); ++i)
      if (folds[i] != f) train_rows.push_back(static_cast<Eigen::Index>(i));
    SvmFeatures<2> tx(static_cast<Eigen::Index>(train_rows.size()), 2);
    std::vector<int> ty;
    for (std::size_t r = 0; r < train_rows.size(); ++r) {
      tx.row(static_cast<Eigen::Index>(r)) = x.row(train_rows[r]);
      ty.push_back(data.y[static_cast<std::size_t>(train_rows[r])]);
    }
    const auto model = train_svm<2>(tx, ty, o);
    SvmPrediction<8> out;
    for (std::size_t i = 0; i < folds.size(); ++i) {
      if (folds[i] != f) continue;
      EXPECT_TRUE(svm_predict(model, Eigen::Vector2d(x.row(static_cast<Eigen::Index>(i)).transpose()), out).accepted());
      EXPECT_EQ(cv.predicted[i], out.label);
      correct += out.label == data.y[i] ? 1 : 0;
    }
  }
  EXPECT_DOUBLE_EQ(cv.accuracy, static_cast<double>(correct) / static_cast<double>(data.y.size()));
  EXPECT_GT(cv.accuracy, 0.6);
}

TEST(SvmTrain, PsoTunedParametersBeatDefaultsOnBadlyScaledFeatures) {
  // Three tight classes along feature 0 (unit scale) with a useless feature 1 a hundred times
  // wider, used raw: libsvm's default gamma = 1/2 makes every kernel value ~0 off the diagonal,
  // so the default model memorises instead of generalising.
  const auto train = ctxfuse::test::gaussian_clusters({{0, 0}, {1.5, 0}, {3, 0}}, {1, 2, 3}, 50, {0.4, 100.0}, 31);
  const auto held_out = ctxfuse::test::gaussian_clusters({{0, 0}, {1.5, 0}, {3, 0}}, {1, 2, 3}, 100, {0.4, 100.0}, 32);
  const SvmFeatures<2> x = train.x;
  SvmTrainOptions defaults;
  defaults.standardize = false;
  const double default_cv = cross_validate_svm<2>(x, train.y, defaults, 5, 1).accuracy;
  SvmTuneOptions tune;
  tune.pso.swarm_size = 8;
  tune.pso.iterations = 8;
  const auto tuned = tune_svm_pso<2>(x, train.y, defaults, tune);
  EXPECT_EQ(tuned.evaluations, 8 * 9);
  EXPECT_GE(tuned.cv_accuracy, default_cv + 0.2) << "default " << default_cv << " tuned " << tuned.cv_accuracy;
  SvmTrainOptions best = defaults;
  best.C = tuned.C;
  best.gamma = tuned.gamma;
  EXPECT_DOUBLE_EQ(cross_validate_svm<2>(x, train.y, best, 5, 1).accuracy, tuned.cv_accuracy);
  // The improvement carries over to unseen data.
  const auto default_model = train_svm<2>(x, train.y, defaults);
  const auto tuned_model = train_svm<2>(x, train.y, best);
  int default_right = 0, tuned_right = 0;
  SvmPrediction<8> out;
  for (Eigen::Index i = 0; i < held_out.x.rows(); ++i) {
    const Eigen::Vector2d q = held_out.x.row(i).transpose();
    EXPECT_TRUE(svm_predict(default_model, q, out).accepted());
    default_right += out.label == held_out.y[static_cast<std::size_t>(i)];
    EXPECT_TRUE(svm_predict(tuned_model, q, out).accepted());
    tuned_right += out.label == held_out.y[static_cast<std::size_t>(i)];
  }
  EXPECT_GE(tuned_right, default_right + 60) << "default " << default_right << " tuned " << tuned_right << " of 300";
}

TEST(SvmTrain, ClassWeightRaisesRecallOfTheWeightedClass) {
  const auto data = ctxfuse::test::gaussian_clusters({{0, 0}, {0.8, 0}}, {0, 1}, 150, {0.6, 0.6}, 14);
  const SvmFeatures<2> x = data.x;
  SvmTrainOptions o;
  const auto count_ones = [&](const SvmModel<2>& m) {
    int n = 0;
    SvmPrediction<8> out;
    for (Eigen::Index i = 0; i < x.rows(); ++i) {
      EXPECT_TRUE(svm_predict(m, Eigen::Vector2d(x.row(i).transpose()), out).accepted());
      n += out.label == 1;
    }
    return n;
  };
  const int plain = count_ones(train_svm<2>(x, data.y, o));
  o.class_weights = {{1, 5.0}};
  const int weighted = count_ones(train_svm<2>(x, data.y, o));
  EXPECT_GT(weighted, plain + 20);
}

// Training at a run-time dimension (Eigen::Dynamic, as the tool trains) gives the fixed-size
// model bit for bit (libsvm sees the same nodes), for both layouts; its cross-validation predicts
// the same labels.
TEST(SvmTrain, RuntimeDimensionTrainsTheFixedSizeModel) {
  const auto data = ctxfuse::test::gaussian_clusters({{0, 0, 0}, {2, 1, 0}, {0, 2, 1}}, {4, 7, 9}, 40, {1.0, 1.5, 0.7}, 5);
  const SvmFeatures<3> x3 = data.x;
  const SvmFeatures<Eigen::Dynamic> xd = data.x;
  for (auto layout : {SvmMulticlass::one_vs_one, SvmMulticlass::one_vs_rest}) {
    SvmTrainOptions o;
    o.multiclass = layout;
    o.probability = true;
    const auto fixed = train_svm<3>(x3, data.y, o);
    const auto runtime = train_svm<Eigen::Dynamic>(xd, data.y, o);
    ASSERT_EQ(runtime.dimension(), 3);
    EXPECT_EQ(runtime.gamma, fixed.gamma);
    EXPECT_EQ(runtime.labels, fixed.labels);
    EXPECT_EQ(Eigen::VectorXd(runtime.input_mean), Eigen::VectorXd(fixed.input_mean));
    EXPECT_EQ(Eigen::VectorXd(runtime.input_std), Eigen::VectorXd(fixed.input_std));
    EXPECT_EQ(Eigen::MatrixXd(runtime.support_vectors), Eigen::MatrixXd(fixed.support_vectors));
    EXPECT_EQ(runtime.coefficients, fixed.coefficients);
    EXPECT_EQ(runtime.rho, fixed.rho);
    EXPECT_EQ(runtime.prob_a, fixed.prob_a);
    EXPECT_EQ(runtime.prob_b, fixed.prob_b);
    const auto folds = stratified_folds(data.y, 4, 3);
    const auto cv_fixed = cross_validate_svm<3>(x3, data.y, o, folds);
    const auto cv_runtime = cross_validate_svm<Eigen::Dynamic>(xd, data.y, o, folds);
    EXPECT_EQ(cv_runtime.predicted, cv_fixed.predicted);
    EXPECT_EQ(cv_runtime.accuracy, cv_fixed.accuracy);
  }
}

TEST(SvmTrain, RejectsBadData) {
  SvmFeatures<2> x(4, 2);
  x << 0, 0, 1, 1, 2, 2, 3, 3;
  const std::vector<int> two = {0, 0, 1, 1}, one = {1, 1, 1, 1}, short_y = {0, 1};
  SvmTrainOptions o;
  EXPECT_THROW(train_svm<2>(x, one, o), std::invalid_argument);
  EXPECT_THROW(train_svm<2>(x, short_y, o), std::invalid_argument);
  SvmFeatures<2> bad = x;
  bad(2, 1) = std::nan("");
  EXPECT_THROW(train_svm<2>(bad, two, o), std::invalid_argument);
  o.C = -1.0;
  EXPECT_THROW(train_svm<2>(x, two, o), std::invalid_argument);
  o.C = 1.0;
  EXPECT_NO_THROW(train_svm<2>(x, two, o));
}

}  // namespace

// Cross-validation of libsvm-trained SVMs over any fold vector (svm_folds.hpp: stratified,
// contiguous blocks, whole groups) and the particle-swarm search over (log2 C, log2 gamma) that
// maximises one of the scores of CvScore on those same folds. Included by svm_train.hpp.
//
// A search on many samples is slow (every evaluation trains one SVM per fold), so the search can
// run on a systematic subsample (every m-th row, which keeps row order, blocks and groups), after
// which the caller fits once on all the data with the parameters found.
#pragma once

#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <stdexcept>
#include <vector>

#include "ctxfuse/classify/pso.hpp"
#include "ctxfuse/classify/svm_folds.hpp"
#include "ctxfuse/classify/svm_options.hpp"
#include "ctxfuse/classify/svm_train.hpp"

namespace ctxfuse::classify {

/// Rows of x (and y) whose group entry equals (equal = true) or differs from `wanted`.
template <int Dim>
std::pair<SvmFeatures<Dim>, std::vector<int>> select_rows(const SvmFeatures<Dim>& x, std::span<const int> y,
                                                          const std::vector<int>& group, int wanted, bool equal) {
  std::vector<Eigen::Index> rows;
  for (std::size_t i = 0; i < group.size(); ++i)
    if ((group[i] == wanted) == equal) rows.push_back(static_cast<Eigen::Index>(i));
  SvmFeatures<Dim> out(static_cast<Eigen::Index>(rows.size()), x.cols());
  std::vector<int> labels(rows.size());
  for (std::size_t r = 0; r < rows.size(); ++r) {
    out.row(static_cast<Eigen::Index>(r)) = x.row(rows[r]);
    labels[r] = y[static_cast<std::size_t>(rows[r])];
  }
  return {std::move(out), std::move(labels)};
}

struct SvmCrossValidation {
  double accuracy = 0.0;           // over the evaluated samples
  double balanced_accuracy = 0.0;  // mean recall over the classes
  double macro_f1 = 0.0;
  double score = 0.0;              // the one asked for
  std::vector<int> predicted;      // out-of-fold prediction per sample (0 where not evaluated)
  std::vector<bool> evaluated;     // false for the samples of a fold whose training part had < 2 classes
  std::vector<int> classes;        // ascending
};

/// Called after each fold: fold index, fold count, samples evaluated so far, score so far.
using SvmCvObserver = std::function<void(int fold, int folds, std::size_t evaluated, double score_so_far)>;

/// Cross-validation over `fold` (fold index per sample). Each fold's model (standardisation
/// included) is fitted on the other folds only; a fold whose training part holds fewer than two
/// classes is not evaluated.
template <int Dim, int MaxClasses = 8>
SvmCrossValidation cross_validate_svm(const SvmFeatures<Dim>& x, std::span<const int> y, const SvmTrainOptions& options,
                                      const std::vector<int>& fold, CvScore score = CvScore::accuracy,
                                      const SvmCvObserver& observe = {}) {
  if (static_cast<std::size_t>(x.rows()) != y.size() || fold.size() != y.size())
    throw std::invalid_argument("cross_validate_svm: sizes of features, labels and folds differ");
  const int folds = fold_count(fold);
  SvmCrossValidation result;
  result.classes = labels_sorted(y);
  result.predicted.assign(y.size(), 0);
  result.evaluated.assign(y.size(), false);
  std::size_t done = 0;
  for (int f = 0; f < folds; ++f) {
    auto [train_x, train_y] = select_rows<Dim>(x, y, fold, f, false);
    if (train_y.empty() || labels_in_order(train_y).size() < 2) continue;
    const auto model = train_svm<Dim, MaxClasses>(train_x, train_y, options);
    SvmPrediction<MaxClasses> out;
    for (std::size_t i = 0; i < y.size(); ++i) {
      if (fold[i] != f) continue;
      const Eigen::Matrix<double, Dim, 1> xi = x.row(static_cast<Eigen::Index>(i)).transpose();
      if (!svm_predict(model, xi, out)) continue;  // NaN/Inf features: left unevaluated
      result.predicted[i] = out.label;
      result.evaluated[i] = true;
      ++done;
    }
    if (observe)
      observe(f, folds, done, score_of(confusion_over(result.classes, y, result.predicted, result.evaluated), score));
  }
  if (done == 0) return result;
  const auto m = confusion_over(result.classes, y, result.predicted, result.evaluated);
  result.accuracy = m.accuracy();
  result.balanced_accuracy = m.balanced_accuracy();
  result.macro_f1 = m.macro_f1();
  result.score = score_of(m, score);
  return result;
}

/// Stratified k-fold cross-validation (the folds of stratified_folds(y, folds, seed)).
template <int Dim, int MaxClasses = 8>
SvmCrossValidation cross_validate_svm(const SvmFeatures<Dim>& x, std::span<const int> y, const SvmTrainOptions& options,
                                      int folds, std::uint64_t seed) {
  if (static_cast<std::size_t>(x.rows()) != y.size()) throw std::invalid_argument("cross_validate_svm: sizes differ");
  return cross_validate_svm<Dim, MaxClasses>(x, y, options, stratified_folds(y, folds, seed));
}


/// PSO over (log2 C, log2 gamma) (log2 C only for the linear kernel) maximising the chosen
/// cross-validated score, as the region-recognition paper tunes its SVM. Probability fitting is
/// off during the search (it does not change the labels' decision function much and costs 5x).
template <int Dim, int MaxClasses = 8>
SvmTuneResult tune_svm_pso(const SvmFeatures<Dim>& x, std::span<const int> y, SvmTrainOptions base,
                           const SvmTuneOptions& tune = {}) {
  if (static_cast<std::size_t>(x.rows()) != y.size()) throw std::invalid_argument("tune_svm_pso: sizes differ");
  if (!tune.fold_of_sample.empty() && tune.fold_of_sample.size() != y.size())
    throw std::invalid_argument("tune_svm_pso: fold_of_sample must have one entry per sample");
  base.probability = false;
  // The search set: all rows, or every m-th.
  const std::size_t n = y.size();
  const std::size_t step =
      tune.max_search_samples > 0 && n > tune.max_search_samples ? (n + tune.max_search_samples - 1) / tune.max_search_samples : 1;
  SvmFeatures<Dim> xs = x;
  std::vector<int> ys(y.begin(), y.end()), folds = tune.fold_of_sample;
  if (step > 1) {
    const std::size_t m = (n + step - 1) / step;
    xs.resize(static_cast<Eigen::Index>(m), x.cols());
    ys.resize(m);
    if (!folds.empty()) folds.resize(m);
    for (std::size_t k = 0; k < m; ++k) {
      xs.row(static_cast<Eigen::Index>(k)) = x.row(static_cast<Eigen::Index>(k * step));
      ys[k] = y[k * step];
      if (!folds.empty()) folds[k] = tune.fold_of_sample[k * step];
    }
  }
  if (folds.empty()) folds = stratified_folds(ys, tune.folds, tune.fold_seed);

  const bool rbf = base.kernel == SvmKernel::rbf;
  const auto start = std::chrono::steady_clock::now();
  SvmTuneResult result;
  result.search_samples = ys.size();
  const auto to_options = [&](double log2_c, double log2_gamma) {
    SvmTrainOptions o = base;
    o.C = std::exp2(log2_c);
    if (rbf) o.gamma = std::exp2(log2_gamma);
    return o;
  };
  const auto report = [&](int it, int evaluations, double best, double log2_c, double log2_gamma) {
    if (!tune.on_progress) return;
    SvmTuneProgress p;
    p.iteration = it;
    p.iterations = tune.pso.iterations;
    p.evaluations = evaluations;
    p.best_score = best;
    p.C = std::exp2(log2_c);
    p.gamma = rbf ? std::exp2(log2_gamma) : 0.0;
    p.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    tune.on_progress(p);
  };
  if (!rbf) {
    const auto objective = [&](const Eigen::Matrix<double, 1, 1>& p) {
      return cross_validate_svm<Dim, MaxClasses>(xs, ys, to_options(p[0], 0.0), folds, tune.score).score;
    };
    const auto observe = [&](int it, const PsoResult<1>& r) { report(it, r.evaluations, r.best_value, r.best_position[0], 0.0); };
    const auto r = pso_maximize<1>(objective, Eigen::Matrix<double, 1, 1>(tune.log2_c_min),
                                   Eigen::Matrix<double, 1, 1>(tune.log2_c_max), tune.pso, observe);
    result.C = std::exp2(r.best_position[0]);
    result.cv_accuracy = r.best_value;
    result.evaluations = r.evaluations;
  } else {
    const auto objective = [&](const Eigen::Vector2d& p) {
      return cross_validate_svm<Dim, MaxClasses>(xs, ys, to_options(p[0], p[1]), folds, tune.score).score;
    };
    const auto observe = [&](int it, const PsoResult<2>& r) {
      report(it, r.evaluations, r.best_value, r.best_position[0], r.best_position[1]);
    };
    const auto r = pso_maximize<2>(objective, Eigen::Vector2d(tune.log2_c_min, tune.log2_gamma_min),
                                   Eigen::Vector2d(tune.log2_c_max, tune.log2_gamma_max), tune.pso, observe);
    result.C = std::exp2(r.best_position[0]);
    result.gamma = std::exp2(r.best_position[1]);
    result.cv_accuracy = r.best_value;
    result.evaluations = r.evaluations;
  }
  return result;
}

}  // namespace ctxfuse::classify

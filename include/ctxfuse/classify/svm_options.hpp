// The options and results of SVM training and tuning (classify/svm_train.hpp,
// classify/svm_tune.hpp), apart from them: those call libsvm, these are plain structs, so a
// header that holds a trained model's tuning record or passes options on (a pipeline's
// inference side) does not need libsvm.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "ctxfuse/classify/pso.hpp"
#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_folds.hpp"

namespace ctxfuse::classify {

struct SvmTrainOptions {
  SvmKernel kernel = SvmKernel::rbf;
  SvmMulticlass multiclass = SvmMulticlass::one_vs_one;
  double C = 1.0;
  double gamma = 0.0;  // <= 0 means 1 / Dim (libsvm's default)
  bool probability = false;
  // Fit mean/std per feature on the training data and train in standardised units. Features
  // with zero spread keep std 1 so that they pass through unchanged.
  bool standardize = true;
  // Optional per-label multipliers of C (libsvm's -wi).
  std::vector<std::pair<int, double>> class_weights;
  double tolerance = 1e-3;  // libsvm -e
  double cache_mb = 200.0;
  bool shrinking = true;
  std::uint32_t seed = 1;  // srand() before each libsvm call
};

/// What the search reports after the initial swarm (iteration 0) and after each iteration.
struct SvmTuneProgress {
  int iteration = 0, iterations = 0;
  int evaluations = 0;  // cross-validations so far
  double best_score = 0.0;
  double C = 1.0, gamma = 0.0;
  double elapsed_s = 0.0;
};

struct SvmTuneOptions {
  // Search box in log2 units, the usual libsvm grid.py range.
  double log2_c_min = -5.0, log2_c_max = 15.0;
  double log2_gamma_min = -15.0, log2_gamma_max = 3.0;
  // Folds: `fold_of_sample` when given (one entry per sample, e.g. block_folds or group_folds),
  // else stratified `folds`-fold with `fold_seed`.
  int folds = 5;
  std::uint64_t fold_seed = 1;
  std::vector<int> fold_of_sample{};
  CvScore score = CvScore::accuracy;
  // > 0: search on every m-th sample, m = ceil(n / max_search_samples) (fold_of_sample thinned
  // alike); 0: on all samples.
  std::size_t max_search_samples = 0;
  PsoOptions pso{.swarm_size = 10, .iterations = 10};
  std::function<void(const SvmTuneProgress&)> on_progress{};
};

struct SvmTuneResult {
  double C = 1.0;
  double gamma = 0.0;        // 0 for the linear kernel
  double cv_accuracy = 0.0;  // best cross-validated score found (the score of tune.score)
  int evaluations = 0;       // cross-validations run
  std::size_t search_samples = 0;
};

}  // namespace ctxfuse::classify

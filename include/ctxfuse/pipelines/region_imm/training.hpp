// Training the region recogniser (region_imm/recogniser.hpp) from labelled logs: the PSO-tuned
// SVM through libsvm (classify/svm_train.hpp, classify/svm_tune.hpp), the HMM's supervised fit,
// the joint vote's weights from a validation log. The one region_imm header that needs libsvm.
#pragma once

#include <span>
#include <stdexcept>
#include <vector>

#include "ctxfuse/classify/hmm.hpp"
#include "ctxfuse/classify/svm_train.hpp"
#include "ctxfuse/classify/svm_tune.hpp"
#include "ctxfuse/pipelines/region_imm/recogniser.hpp"

namespace ctxfuse::pipelines::region_imm {

struct RecogniserOptions {
  // PSO over (log2 C, log2 gamma), 3-fold CV; a small swarm is enough for two parameters.
  classify::SvmTuneOptions tune{.log2_c_min = -5.0, .log2_c_max = 10.0, .log2_gamma_min = -8.0, .log2_gamma_max = 3.0,
                                .folds = 3, .fold_seed = 1, .pso = {.swarm_size = 6, .iterations = 5, .seed = 1}};
  classify::HmmFitOptions hmm{};
};

/// PSO-SVM (one-vs-rest RBF) and HMM trained on the labelled logs in `train` (the SVM on all
/// their epochs pooled, the HMM on each log as its own sequence, so that no transition is
/// counted across the seam between two logs); per-region accuracies of both on `validate` give
/// the joint vote's weights. Throws std::invalid_argument when `train` is empty, when a log's
/// labels do not match its epochs, or a label is not a region.
template <class = void>
Recogniser train_recogniser(std::span<const LabelledFeatures> train, const LabelledFeatures& validate,
                            const RecogniserOptions& opts = {}) {
  if (train.empty()) throw std::invalid_argument("region_imm: train_recogniser needs at least one training log");
  for (const auto& f : train) check_labels(f);
  check_labels(validate);
  Recogniser r;
  std::size_t rows = 0;
  for (const auto& f : train) rows += f.features.x.size();
  classify::SvmFeatures<2> X(static_cast<Eigen::Index>(rows), 2);
  std::vector<int> labels;
  labels.reserve(rows);
  std::vector<classify::LabelledSequence<2>> sequences;
  for (const auto& f : train) {
    for (std::size_t i = 0; i < f.features.x.size(); ++i)
      X.row(static_cast<Eigen::Index>(labels.size() + i)) = f.features.x[i].transpose();
    labels.insert(labels.end(), f.labels.begin(), f.labels.end());
    sequences.push_back({std::span<const Feature>(f.features.x), std::span<const int>(f.labels)});
  }
  classify::SvmTrainOptions so;
  so.kernel = classify::SvmKernel::rbf;
  so.multiclass = classify::SvmMulticlass::one_vs_rest;
  r.tuned = classify::tune_svm_pso<2, 3>(X, labels, so, opts.tune);
  so.C = r.tuned.C;
  so.gamma = r.tuned.gamma;
  r.svm = classify::train_svm<2, 3>(X, labels, so);
  r.hmm = classify::fit_supervised<kRegions, 2>(std::span<const classify::LabelledSequence<2>>(sequences), opts.hmm);

  Recognition v;
  v.svm = svm_labels(r.svm, validate.features);
  v.hmm = viterbi_labels(r.hmm, validate.features);
  r.validation_accuracy[0] = classify::per_region_accuracy<kRegions>(validate.labels, v.svm);
  r.validation_accuracy[1] = classify::per_region_accuracy<kRegions>(validate.labels, v.hmm);
  r.vote = classify::WeightedVote<kRegions, 2>::from_accuracies(r.validation_accuracy);
  return r;
}

/// One training log.
template <class = void>
Recogniser train_recogniser(const LabelledFeatures& train, const LabelledFeatures& validate,
                            const RecogniserOptions& opts = {}) {
  return train_recogniser(std::span<const LabelledFeatures>(&train, 1), validate, opts);
}

}  // namespace ctxfuse::pipelines::region_imm

// Region recognition of the region paper (paper A): per-epoch GNSS features (number of
// tracked satellites, mean C/N0) -> PSO-SVM + HMM + joint vote -> recognised region per epoch.
// Features come from the receiver's epochs (messages::SatEpoch) only; the labels that train and
// validate the classifiers are the caller's (from a labelled log's truth: eval/truth.hpp).
//
// recognise() runs the SVM per epoch and the HMM's Viterbi path over the whole log (what the
// paper reports, and what an offline replay of a recording can do); hmm_posteriors() is the
// causal forward filter, what an online system knows at each epoch.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "ctxfuse/classify/hmm.hpp"
#include "ctxfuse/classify/joint.hpp"
#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_train.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/pipelines/region_imm/settings.hpp"

namespace ctxfuse::pipelines::region_imm {

using Feature = Eigen::Vector2d;  // (TNVS, mean SNR [dB-Hz])

/// Features of every receiver epoch, in time order.
struct FeatureSeries {
  std::vector<double> t;
  std::vector<Feature> x;
};

/// A log's features with a region label per epoch (0 outdoor, 1 transition, 2 indoor).
struct LabelledFeatures {
  FeatureSeries features;
  std::vector<int> labels;
};

/// (number of tracked satellites, their mean C/N0) per epoch; an epoch without satellites has
/// mean C/N0 0 (what a receiver that tracks nothing reports as its average).
inline FeatureSeries gnss_features(std::span<const messages::SatEpoch> epochs) {
  FeatureSeries f;
  f.t.reserve(epochs.size());
  f.x.reserve(epochs.size());
  for (const auto& e : epochs) {
    f.t.push_back(e.t);
    f.x.emplace_back(static_cast<double>(e.sats.size()), e.mean_cn0());
  }
  return f;
}

inline void check_labels(const LabelledFeatures& f) {
  if (f.labels.size() != f.features.x.size())
    throw std::invalid_argument("region_imm: " + std::to_string(f.labels.size()) + " labels for " +
                                std::to_string(f.features.x.size()) + " epochs");
  for (int l : f.labels)
    if (l < 0 || l >= kRegions) throw std::invalid_argument("region_imm: label " + std::to_string(l) + " is not a region (0, 1, 2)");
}

struct RecogniserOptions {
  // PSO over (log2 C, log2 gamma), 3-fold CV; a small swarm is enough for two parameters.
  classify::SvmTuneOptions tune{.log2_c_min = -5.0, .log2_c_max = 10.0, .log2_gamma_min = -8.0, .log2_gamma_max = 3.0,
                                .folds = 3, .fold_seed = 1, .pso = {.swarm_size = 6, .iterations = 5, .seed = 1}};
  classify::HmmFitOptions hmm{};
};

struct Recogniser {
  classify::SvmModel<2, 3> svm;
  classify::GaussianHmm<kRegions, 2> hmm;
  classify::WeightedVote<kRegions, 2> vote;
  classify::SvmTuneResult tuned;
  std::array<std::array<double, kRegions>, 2> validation_accuracy{};  // [svm, hmm][region]
};

struct Recognition {
  std::vector<int> svm, hmm, joint;  // one label per epoch of the FeatureSeries
};

inline std::vector<int> svm_labels(const classify::SvmModel<2, 3>& model, const FeatureSeries& f) {
  std::vector<int> out;
  out.reserve(f.x.size());
  for (const auto& x : f.x) {
    classify::SvmPrediction<3> p;
    out.push_back(classify::svm_predict(model, x, p) == classify::SvmStatus::ok ? p.label : -1);
  }
  return out;
}

inline Recognition recognise(const Recogniser& r, const FeatureSeries& f) {
  Recognition out;
  out.svm = svm_labels(r.svm, f);
  out.hmm = classify::viterbi<kRegions, 2>(r.hmm, std::span<const Feature>(f.x)).path;
  out.joint.resize(f.x.size());
  for (std::size_t i = 0; i < f.x.size(); ++i) out.joint[i] = r.vote({out.svm[i], out.hmm[i]});
  return out;
}

/// PSO-SVM (one-vs-rest RBF) and HMM trained on the labelled logs in `train` (the SVM on all
/// their epochs pooled, the HMM on each log as its own sequence, so that no transition is
/// counted across the seam between two logs); per-region accuracies of both on `validate` give
/// the joint vote's weights. Throws std::invalid_argument when `train` is empty, when a log's
/// labels do not match its epochs, or a label is not a region.
inline Recogniser train_recogniser(std::span<const LabelledFeatures> train, const LabelledFeatures& validate,
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
  v.hmm = classify::viterbi<kRegions, 2>(r.hmm, std::span<const Feature>(validate.features.x)).path;
  r.validation_accuracy[0] = classify::per_region_accuracy<kRegions>(validate.labels, v.svm);
  r.validation_accuracy[1] = classify::per_region_accuracy<kRegions>(validate.labels, v.hmm);
  r.vote = classify::WeightedVote<kRegions, 2>::from_accuracies(r.validation_accuracy);
  return r;
}

/// One training log.
inline Recogniser train_recogniser(const LabelledFeatures& train, const LabelledFeatures& validate,
                                   const RecogniserOptions& opts = {}) {
  return train_recogniser(std::span<const LabelledFeatures>(&train, 1), validate, opts);
}

/// The HMM's causal region posterior at every epoch (forward filter: p(region_t | features up
/// to t)), what an online system knows; an epoch the filter cannot use (non-finite features,
/// zero likelihood) repeats the previous posterior, and the uniform one before the first.
inline std::vector<Vector<kRegions>> hmm_posteriors(const Recogniser& r, const FeatureSeries& f) {
  std::vector<Vector<kRegions>> out;
  out.reserve(f.x.size());
  classify::HmmForwardFilter<kRegions, 2> filter(r.hmm);
  Vector<kRegions> last = Vector<kRegions>::Constant(1.0 / kRegions);
  for (const auto& x : f.x) {
    if (filter.step(x) == classify::FilterStatus::ok) last = filter.posterior();
    out.push_back(last);
  }
  return out;
}

inline double accuracy(std::span<const int> truth, std::span<const int> predicted) {
  if (truth.size() != predicted.size() || truth.empty()) return 0.0;
  std::size_t ok = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) ok += truth[i] == predicted[i] ? 1 : 0;
  return static_cast<double>(ok) / static_cast<double>(truth.size());
}

/// The recognised regions as the region IMMs take them: one label (and optionally the HMM's
/// posterior) per receiver epoch, looked up by time.
inline RegionTrack region_track(const FeatureSeries& f, std::vector<int> labels, std::vector<Vector<kRegions>> posteriors = {}) {
  if (labels.size() != f.t.size() || (!posteriors.empty() && posteriors.size() != f.t.size()))
    throw std::invalid_argument("region_imm: region_track needs one label (and posterior) per epoch");
  RegionTrack r;
  r.t = f.t;
  r.label = std::move(labels);
  r.posterior = std::move(posteriors);
  return r;
}

}  // namespace ctxfuse::pipelines::region_imm

// Region recognition of the region paper (paper A): per-epoch GNSS features (number of
// tracked satellites, mean C/N0) -> PSO-SVM + HMM + joint vote -> recognised region per epoch.
// Features come from the receiver's epochs (messages::SatEpoch) only; the labels that train and
// validate the classifiers are the caller's (from a labelled log's truth: eval/truth.hpp).
// Training (PSO-SVM through libsvm, the HMM's fit) is in region_imm/training.hpp: this header,
// the inference side, does not need libsvm.
//
// recognise_causal() is what an online system has: at each epoch the SVM's label, the argmax of
// the HMM's forward filter (p(region | features up to that epoch), hmm_posteriors()) and the
// joint vote of the two, so a label never depends on a later epoch. recognise() runs the SVM
// per epoch and the HMM's Viterbi path over the whole log: what the paper reports as its
// recognition accuracy, which an offline replay can do and an online system cannot (a Viterbi
// label at t depends on the epochs after t). The demo and `region-study` still hand the IMMs
// recognise()'s labels (the figures of docs/results.md); the demo prints the causal accuracy
// beside them.
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
#include "ctxfuse/classify/svm_options.hpp"
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

template <class = void>
std::vector<int> svm_labels(const classify::SvmModel<2, 3>& model, const FeatureSeries& f) {
  std::vector<int> out;
  out.reserve(f.x.size());
  for (const auto& x : f.x) {
    classify::SvmPrediction<3> p;
    out.push_back(classify::svm_predict(model, x, p).accepted() ? p.label : -1);
  }
  return out;
}

/// The HMM's Viterbi path over a drive's features; a non-finite feature throws
/// std::invalid_argument naming its epoch.
template <class = void>
std::vector<int> viterbi_labels(const classify::GaussianHmm<kRegions, 2>& hmm, const FeatureSeries& f) {
  auto v = classify::viterbi<kRegions, 2>(hmm, std::span<const Feature>(f.x));
  if (!v.status)
    throw std::invalid_argument("region recogniser: the features of epoch " + std::to_string(v.refused_at) +
                                " are not finite");
  return std::move(v.path);
}

template <class = void>
Recognition recognise(const Recogniser& r, const FeatureSeries& f) {
  Recognition out;
  out.svm = svm_labels(r.svm, f);
  out.hmm = viterbi_labels(r.hmm, f);
  out.joint.resize(f.x.size());
  for (std::size_t i = 0; i < f.x.size(); ++i) out.joint[i] = r.vote({out.svm[i], out.hmm[i]});
  return out;
}

/// The HMM's causal region posterior at every epoch (forward filter: p(region_t | features up
/// to t)), what an online system knows; an epoch the filter cannot use (non-finite features,
/// zero likelihood) repeats the previous posterior, and the uniform one before the first.
template <class = void>
std::vector<Vector<kRegions>> hmm_posteriors(const Recogniser& r, const FeatureSeries& f) {
  std::vector<Vector<kRegions>> out;
  out.reserve(f.x.size());
  classify::HmmForwardFilter<kRegions, 2> filter(r.hmm);
  Vector<kRegions> last = Vector<kRegions>::Constant(1.0 / kRegions);
  for (const auto& x : f.x) {
    if (filter.step(x).accepted()) last = filter.posterior();
    out.push_back(last);
  }
  return out;
}

/// The causal recognition (header): per epoch the SVM's label, the HMM forward filter's most
/// probable region (`hmm`) and their joint vote, each from that epoch and earlier ones only.
template <class = void>
Recognition recognise_causal(const Recogniser& r, const FeatureSeries& f) {
  Recognition out;
  out.svm = svm_labels(r.svm, f);
  const std::vector<Vector<kRegions>> post = hmm_posteriors(r, f);
  out.hmm.resize(f.x.size());
  out.joint.resize(f.x.size());
  for (std::size_t i = 0; i < f.x.size(); ++i) {
    Eigen::Index best = 0;
    post[i].maxCoeff(&best);
    out.hmm[i] = static_cast<int>(best);
    out.joint[i] = r.vote({out.svm[i], out.hmm[i]});
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

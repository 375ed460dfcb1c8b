// Joint region decision of several classifiers (region paper, eq. 18-28), implemented as the
// weighted vote the digest prescribes: each classifier c has a validation accuracy P_{c,k} for
// every region k; its weight for region k is w_{c,k} = P_{c,k} / sum_c' P_{c',k}; the score of
// region k is the sum of w_{c,k} over the classifiers that vote k; the decision is the argmax.
// With two classifiers (SVM first, HMM second) this is w_s = P_S/(P_S+P_H), w_h = P_H/(P_S+P_H).
//
// Ties (equal best scores, e.g. equal accuracies and disagreeing votes): the region voted by
// the classifier listed first wins (the SVM in the paper's arrangement, its stronger model).
// Regions no classifier has any accuracy for (sum of P = 0) give both classifiers weight
// 1/num_classifiers, so that the vote degrades to a plain majority there instead of 0/0.
#pragma once

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace ctxfuse::classify {

template <int NumRegions, int NumClassifiers = 2>
struct WeightedVote {
  static_assert(NumRegions >= 1 && NumClassifiers >= 1);
  /// weights[c][k]: weight of classifier c when it votes region k.
  std::array<std::array<double, NumRegions>, NumClassifiers> weights{};

  /// accuracy[c][k] = P_{c,k} in [0, 1]; throws std::invalid_argument naming the entry otherwise.
  static WeightedVote from_accuracies(
      const std::array<std::array<double, NumRegions>, NumClassifiers>& accuracy) {
    WeightedVote vote;
    for (int k = 0; k < NumRegions; ++k) {
      double total = 0.0;
      for (int c = 0; c < NumClassifiers; ++c) {
        const double p = accuracy[c][k];
        if (!(p >= 0.0 && p <= 1.0))
          throw std::invalid_argument("WeightedVote: accuracy of classifier " + std::to_string(c) +
                                      " for region " + std::to_string(k) + " is not in [0, 1]");
        total += p;
      }
      for (int c = 0; c < NumClassifiers; ++c)
        vote.weights[c][k] = total > 0.0 ? accuracy[c][k] / total : 1.0 / NumClassifiers;
    }
    return vote;
  }

  struct Decision {
    int region = -1;  // -1 only when every vote was out of range
    std::array<double, NumRegions> scores{};
  };

  /// votes[c] is classifier c's region; a vote outside [0, NumRegions) (e.g. -1 for "no
  /// decision") is ignored.
  Decision decide(const std::array<int, NumClassifiers>& votes) const {
    Decision d;
    for (int c = 0; c < NumClassifiers; ++c) {
      const int k = votes[c];
      if (k >= 0 && k < NumRegions) d.scores[k] += weights[c][k];
    }
    double best = -1.0;
    for (int c = 0; c < NumClassifiers; ++c) {  // classifier order breaks ties
      const int k = votes[c];
      if (k >= 0 && k < NumRegions && d.scores[k] > best) {
        best = d.scores[k];
        d.region = k;
      }
    }
    return d;
  }

  int operator()(const std::array<int, NumClassifiers>& votes) const { return decide(votes).region; }
};

/// Per-region accuracy P_k = (correct predictions with truth k) / (samples with truth k);
/// regions absent from the truth get 0. Throws on length mismatch.
template <int NumRegions, typename TruthRange, typename PredictedRange>
std::array<double, NumRegions> per_region_accuracy(const TruthRange& truth,
                                                   const PredictedRange& predicted) {
  if (std::size(truth) != std::size(predicted))
    throw std::invalid_argument("per_region_accuracy: truth and predictions differ in length");
  std::array<double, NumRegions> correct{}, total{};
  auto p = std::begin(predicted);
  for (auto t = std::begin(truth); t != std::end(truth); ++t, ++p) {
    const int k = *t;
    if (k < 0 || k >= NumRegions) continue;
    total[k] += 1.0;
    if (*p == k) correct[k] += 1.0;
  }
  std::array<double, NumRegions> out{};
  for (int k = 0; k < NumRegions; ++k) out[k] = total[k] > 0.0 ? correct[k] / total[k] : 0.0;
  return out;
}

}  // namespace ctxfuse::classify

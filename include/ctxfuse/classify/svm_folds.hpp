// Validation folds and scores for classifier training, without libsvm:
// - stratified_folds: each class shuffled and dealt round-robin (rows independent of each other);
// - block_folds: contiguous blocks of rows in their order (time-ordered data: neighbouring
//   epochs stay on one side);
// - group_folds: whole groups (recordings, heights, days) per fold, leave-one-group-out or k
//   folds of about equal size;
// - inverse-frequency class weights and the score a search maximises (accuracy, balanced
//   accuracy, macro-F1).
// A fold vector gives each sample its fold index 0..k-1; fold f's model is trained on every
// sample whose index is not f.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ctxfuse/classify/confusion_matrix.hpp"

namespace ctxfuse::classify {

/// Distinct labels in order of first appearance (libsvm's class order).
inline std::vector<int> labels_in_order(std::span<const int> y) {
  std::vector<int> out;
  for (int v : y)
    if (std::find(out.begin(), out.end(), v) == out.end()) out.push_back(v);
  return out;
}

/// Distinct labels, ascending (the order every report uses).
inline std::vector<int> labels_sorted(std::span<const int> y) {
  auto out = labels_in_order(y);
  std::sort(out.begin(), out.end());
  return out;
}

/// Fold index (0..folds-1) of every sample: each class's samples are shuffled with the seed and
/// dealt round-robin, so every fold holds each class in proportion.
inline std::vector<int> stratified_folds(std::span<const int> y, int folds, std::uint64_t seed) {
  if (folds < 2) throw std::invalid_argument("stratified_folds: need at least 2 folds");
  std::mt19937_64 rng(seed);
  std::vector<int> fold(y.size(), 0);
  int next_fold = 0;
  for (int label : labels_in_order(y)) {
    std::vector<std::size_t> members;
    for (std::size_t i = 0; i < y.size(); ++i)
      if (y[i] == label) members.push_back(i);
    // Fisher-Yates with our own bounded draw: the order is the same with every standard library.
    for (std::size_t i = members.size(); i > 1; --i) {
      const auto j = static_cast<std::size_t>(rng() % i);
      std::swap(members[i - 1], members[j]);
    }
    for (std::size_t i : members) {
      fold[i] = next_fold;
      next_fold = (next_fold + 1) % folds;
    }
  }
  return fold;
}

/// True for the samples of a stratified test split of about `test_fraction` of each class.
inline std::vector<bool> stratified_split(std::span<const int> y, double test_fraction, std::uint64_t seed) {
  if (!(test_fraction > 0.0 && test_fraction < 1.0)) throw std::invalid_argument("stratified_split: test_fraction must be in (0, 1)");
  std::mt19937_64 rng(seed);
  std::vector<bool> is_test(y.size(), false);
  for (int label : labels_in_order(y)) {
    std::vector<std::size_t> members;
    for (std::size_t i = 0; i < y.size(); ++i)
      if (y[i] == label) members.push_back(i);
    for (std::size_t i = members.size(); i > 1; --i) std::swap(members[i - 1], members[static_cast<std::size_t>(rng() % i)]);
    const auto n_test = static_cast<std::size_t>(std::llround(test_fraction * static_cast<double>(members.size())));
    for (std::size_t i = 0; i < n_test; ++i) is_test[members[i]] = true;
  }
  return is_test;
}

/// Contiguous blocks: sample i of n goes to fold floor(i * folds / n), so fold f holds rows
/// [ceil(f n / k), ceil((f+1) n / k)) and block sizes differ by at most one.
inline std::vector<int> block_folds(std::size_t n, int folds) {
  if (folds < 2) throw std::invalid_argument("block_folds: need at least 2 folds");
  if (n < static_cast<std::size_t>(folds))
    throw std::invalid_argument("block_folds: " + std::to_string(n) + " samples cannot fill " + std::to_string(folds) + " folds");
  std::vector<int> fold(n);
  for (std::size_t i = 0; i < n; ++i) fold[i] = static_cast<int>(i * static_cast<std::size_t>(folds) / n);
  return fold;
}

/// Whole groups per fold. folds <= 0 or folds >= number of groups: one fold per group
/// (leave-one-group-out), folds numbered in order of the groups' first appearance. Otherwise
/// groups are placed largest first (ties: first appearance) into the fold holding the fewest
/// samples so far (ties: lowest index), so folds are of about equal size.
inline std::vector<int> group_folds(std::span<const int> groups, int folds = 0) {
  const auto order = labels_in_order(groups);
  if (order.size() < 2) throw std::invalid_argument("group_folds: need at least 2 groups, got " + std::to_string(order.size()));
  std::map<int, int> fold_of;
  if (folds <= 0 || static_cast<std::size_t>(folds) >= order.size()) {
    for (std::size_t g = 0; g < order.size(); ++g) fold_of[order[g]] = static_cast<int>(g);
  } else {
    std::map<int, std::size_t> size;
    for (int g : groups) ++size[g];
    std::vector<int> by_size = order;
    std::stable_sort(by_size.begin(), by_size.end(), [&](int a, int b) { return size[a] > size[b]; });
    std::vector<std::size_t> load(static_cast<std::size_t>(folds), 0);
    for (int g : by_size) {
      const auto f = static_cast<std::size_t>(std::min_element(load.begin(), load.end()) - load.begin());
      fold_of[g] = static_cast<int>(f);
      load[f] += size[g];
    }
  }
  std::vector<int> fold(groups.size());
  for (std::size_t i = 0; i < groups.size(); ++i) fold[i] = fold_of[groups[i]];
  return fold;
}

/// Number of folds in a fold vector (largest index + 1).
inline int fold_count(std::span<const int> fold) {
  return fold.empty() ? 0 : *std::max_element(fold.begin(), fold.end()) + 1;
}

/// C multipliers w_c = n / (k n_c) per label (inverse frequency, mean weight over samples 1),
/// in ascending label order.
inline std::vector<std::pair<int, double>> inverse_frequency_weights(std::span<const int> y) {
  std::map<int, std::size_t> count;
  for (int v : y) ++count[v];
  std::vector<std::pair<int, double>> w;
  for (const auto& [label, n] : count)
    w.emplace_back(label, static_cast<double>(y.size()) / (static_cast<double>(count.size()) * static_cast<double>(n)));
  return w;
}

/// What a cross-validation reports and a parameter search maximises.
enum class CvScore { accuracy, balanced_accuracy, macro_f1 };

constexpr std::string_view to_string(CvScore s) {
  switch (s) {
    case CvScore::accuracy: return "accuracy";
    case CvScore::balanced_accuracy: return "balanced-accuracy";
    case CvScore::macro_f1: return "macro-f1";
  }
  return "?";
}

inline double score_of(const ConfusionMatrix& m, CvScore s) {
  switch (s) {
    case CvScore::accuracy: return m.accuracy();
    case CvScore::balanced_accuracy: return m.balanced_accuracy();
    case CvScore::macro_f1: return m.macro_f1();
  }
  return m.accuracy();
}

/// Confusion matrix over `classes` (index = position in `classes`) of the samples where
/// `include` is true (all when empty); labels outside `classes` throw std::out_of_range.
inline ConfusionMatrix confusion_over(std::span<const int> classes, std::span<const int> truth,
                                            std::span<const int> predicted, const std::vector<bool>& include = {}) {
  const auto index = [&](int label) {
    const auto it = std::find(classes.begin(), classes.end(), label);
    if (it == classes.end()) throw std::out_of_range("confusion_over: label " + std::to_string(label) + " is not a known class");
    return static_cast<int>(it - classes.begin());
  };
  ConfusionMatrix m(static_cast<int>(classes.size()));
  for (std::size_t i = 0; i < truth.size(); ++i)
    if (include.empty() || include[i]) m.add(index(truth[i]), index(predicted[i]));
  return m;
}

}  // namespace ctxfuse::classify

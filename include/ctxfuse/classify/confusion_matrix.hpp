// Classification scores: a confusion matrix with accuracy, balanced accuracy, macro-F1 and
// per-class precision, recall and F1. Classes are 0 .. n-1; rows are the true class, columns the
// predicted class.
#pragma once

#include <cstddef>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace ctxfuse::classify {

class ConfusionMatrix {
 public:
  explicit ConfusionMatrix(int num_classes) : n_(num_classes) {
    if (num_classes < 1 || num_classes > 10000)
      throw std::invalid_argument("ConfusionMatrix: num_classes must be within [1, 10000], got " + std::to_string(num_classes));
    counts_.assign(static_cast<std::size_t>(n_) * static_cast<std::size_t>(n_), 0);
  }

  /// Builds the matrix from two equally long label sequences.
  static ConfusionMatrix from_labels(std::span<const int> truth, std::span<const int> predicted, int num_classes) {
    if (truth.size() != predicted.size())
      throw std::invalid_argument("ConfusionMatrix: " + std::to_string(truth.size()) + " true labels but " +
                                  std::to_string(predicted.size()) + " predictions");
    ConfusionMatrix m(num_classes);
    for (std::size_t i = 0; i < truth.size(); ++i) m.add(truth[i], predicted[i]);
    return m;
  }

  /// Counts one sample. Throws std::out_of_range naming the bad label; the matrix is unchanged.
  void add(int truth, int predicted) {
    check(truth, "true");
    check(predicted, "predicted");
    ++counts_[index(truth, predicted)];
    ++total_;
  }

  int num_classes() const { return n_; }
  std::size_t count(int truth, int predicted) const { return counts_[index(truth, predicted)]; }
  std::size_t total() const { return total_; }
  /// Samples whose true class is k.
  std::size_t support(int k) const {
    std::size_t s = 0;
    for (int p = 0; p < n_; ++p) s += count(k, p);
    return s;
  }
  /// Samples predicted as class k.
  std::size_t predicted_count(int k) const {
    std::size_t s = 0;
    for (int t = 0; t < n_; ++t) s += count(t, k);
    return s;
  }

  /// Fraction of samples on the diagonal; NaN when empty.
  double accuracy() const {
    if (total_ == 0) return std::numeric_limits<double>::quiet_NaN();
    std::size_t diag = 0;
    for (int k = 0; k < n_; ++k) diag += count(k, k);
    return static_cast<double>(diag) / static_cast<double>(total_);
  }
  /// Mean recall over the classes that occur (support > 0); NaN when empty. Equals accuracy when
  /// every class has the same support, and 1/k for a classifier that always answers one class.
  double balanced_accuracy() const {
    double sum = 0.0;
    int classes = 0;
    for (int k = 0; k < n_; ++k)
      if (support(k) > 0) {
        sum += recall(k);
        ++classes;
      }
    return classes == 0 ? std::numeric_limits<double>::quiet_NaN() : sum / classes;
  }
  /// Mean F1 over the classes that occur; a class that occurs but is never predicted right
  /// counts 0 (F1 = 2 TP / (2 TP + FP + FN)). NaN when empty.
  double macro_f1() const {
    double sum = 0.0;
    int classes = 0;
    for (int k = 0; k < n_; ++k) {
      const auto sup = support(k);
      if (sup == 0) continue;
      const double tp = static_cast<double>(count(k, k));
      const double fp = static_cast<double>(predicted_count(k)) - tp, fn = static_cast<double>(sup) - tp;
      sum += 2.0 * tp / (2.0 * tp + fp + fn);
      ++classes;
    }
    return classes == 0 ? std::numeric_limits<double>::quiet_NaN() : sum / classes;
  }
  /// TP / (TP + FP) for class k; NaN when nothing was predicted as k.
  double precision(int k) const {
    check(k, "class");
    const auto pred = predicted_count(k);
    return pred == 0 ? std::numeric_limits<double>::quiet_NaN() : static_cast<double>(count(k, k)) / static_cast<double>(pred);
  }
  /// TP / (TP + FN) for class k; NaN when class k never occurs.
  double recall(int k) const {
    check(k, "class");
    const auto sup = support(k);
    return sup == 0 ? std::numeric_limits<double>::quiet_NaN() : static_cast<double>(count(k, k)) / static_cast<double>(sup);
  }
  /// Harmonic mean of precision and recall; NaN when either is undefined, 0 when both are 0.
  double f1(int k) const {
    const double p = precision(k), r = recall(k);
    if (p != p || r != r) return std::numeric_limits<double>::quiet_NaN();
    return p + r == 0.0 ? 0.0 : 2.0 * p * r / (p + r);
  }

 private:
  std::size_t index(int t, int p) const { return static_cast<std::size_t>(t) * static_cast<std::size_t>(n_) + static_cast<std::size_t>(p); }
  void check(int k, const char* what) const {
    if (k < 0 || k >= n_)
      throw std::out_of_range(std::string("ConfusionMatrix: ") + what + " label " + std::to_string(k) + " is outside [0, " +
                              std::to_string(n_ - 1) + "]");
  }
  int n_;
  std::vector<std::size_t> counts_;
  std::size_t total_ = 0;
};

}  // namespace ctxfuse::classify

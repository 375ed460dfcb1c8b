// The SVM model: one representation for every machine layout, a set of support vectors (stored
// structure-of-arrays, one contiguous column per feature) and a dense coefficient matrix with one
// row per binary machine, so machine m's decision value is
//     f_m(x) = sum_s coefficients(m, s) * K(x', sv_s) - rho_m,   x' = (x - input_mean) / input_std.
// A libsvm one-vs-one model becomes k(k-1)/2 rows (zero where a support vector takes no part in a
// pair); a one-vs-rest model becomes k rows over the union of the k machines' support vectors.
// The dense layout costs a few multiply-adds per zero but lets the RBF kernel be evaluated once
// per support vector, in vectorised blocks, whatever the class count.
//
// The feature dimension is fixed at compile time, or (Dim = Eigen::Dynamic) taken from the file
// or the training data at run time. The model's check (svm_model_problem) and its derived
// fields (finalize_svm_model) are here; prediction is in svm.hpp, files in svm_io.hpp, training
// in svm_train.hpp.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>

#include "ctxfuse/core/error.hpp"

namespace ctxfuse::classify {

enum class SvmKernel : std::uint8_t { linear, rbf };
enum class SvmMulticlass : std::uint8_t { one_vs_one, one_vs_rest };

constexpr std::string_view to_string(SvmKernel k) { return k == SvmKernel::linear ? "linear" : "rbf"; }
constexpr std::string_view to_string(SvmMulticlass m) {
  return m == SvmMulticlass::one_vs_one ? "ovo" : "ovr";
}

/// Number of binary machines for k classes: k(k-1)/2 pairs for one-vs-one, except that a
/// two-class problem is always a single machine; k for one-vs-rest with k > 2.
constexpr int svm_machine_count(SvmMulticlass layout, int num_classes) {
  if (num_classes <= 2) return 1;
  return layout == SvmMulticlass::one_vs_one ? num_classes * (num_classes - 1) / 2 : num_classes;
}

/// Largest machine count a model with at most MaxClasses classes can have.
constexpr int svm_max_machines(int max_classes) {
  return std::max(max_classes * (max_classes - 1) / 2, max_classes);
}

namespace svm_detail {
/// A fixed-size Eigen object filled with `value`; an empty one for a run-time size.
template <class M>
M filled_or_empty(double value) {
  if constexpr (M::SizeAtCompileTime == Eigen::Dynamic) {
    return M();
  } else {
    return M::Constant(value);
  }
}
}  // namespace svm_detail

template <int Dim, int MaxClasses = 8>
struct SvmModel {
  static_assert(Dim >= 1 || Dim == Eigen::Dynamic, "feature dimension must be positive (or Eigen::Dynamic)");
  static_assert(MaxClasses >= 2 && MaxClasses <= 32, "MaxClasses must be in [2, 32]");
  static constexpr int kDim = Dim;
  static constexpr int kMaxClasses = MaxClasses;
  static constexpr int kMaxMachines = svm_max_machines(MaxClasses);
  using Feature = Eigen::Matrix<double, Dim, 1>;
  using SupportVectors = Eigen::Matrix<double, Eigen::Dynamic, Dim, Eigen::ColMajor>;
  using Coefficients = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

  SvmKernel kernel = SvmKernel::rbf;
  // For two classes both layouts are the same single machine; the field then only records intent.
  SvmMulticlass multiclass = SvmMulticlass::one_vs_one;
  // RBF width: K(a, b) = exp(-gamma |a - b|^2); unused for linear. 1 / Dim unless set (a
  // run-time dimension has no default: its loaders and training set it).
  double gamma = Dim == Eigen::Dynamic ? 0.0 : 1.0 / Dim;
  int num_classes = 0;
  // Class labels as in the training data. One-vs-one pair (i, j), i < j, votes labels[i] when its
  // decision value is > 0 (libsvm's convention); one-vs-rest machine m says labels[m] when > 0.
  std::array<int, MaxClasses> labels{};
  // Standardisation fitted on the training data; libsvm files carry none (mean 0, std 1). With a
  // run-time dimension, input_mean's size is the model's dimension.
  Feature input_mean = svm_detail::filled_or_empty<Feature>(0.0);
  Feature input_std = svm_detail::filled_or_empty<Feature>(1.0);
  SupportVectors support_vectors;  // num_sv x Dim, in standardised units
  Coefficients coefficients;       // num_machines x num_sv: y_i alpha_i per machine
  std::array<double, kMaxMachines> rho{};
  // Platt sigmoid per machine: P(positive side) = 1 / (1 + exp(prob_a * f + prob_b)).
  bool has_probability = false;
  std::array<double, kMaxMachines> prob_a{};
  std::array<double, kMaxMachines> prob_b{};
  // Derived by finalize_svm_model for the linear kernel: w_m = sum_s coefficients(m, s) sv_s.
  Eigen::Matrix<double, kMaxMachines, Dim> linear_weights =
      svm_detail::filled_or_empty<Eigen::Matrix<double, kMaxMachines, Dim>>(0.0);

  int dimension() const {
    if constexpr (Dim == Eigen::Dynamic) {
      return static_cast<int>(input_mean.size());
    } else {
      return Dim;
    }
  }
  int num_machines() const { return svm_machine_count(multiclass, num_classes); }
  Eigen::Index num_support_vectors() const { return support_vectors.rows(); }
};

/// Describes what is wrong with a model ("" when it is usable). Checked by finalize_svm_model.
template <int Dim, int MaxClasses>
std::string svm_model_problem(const SvmModel<Dim, MaxClasses>& m) {
  if (m.num_classes < 2 || m.num_classes > MaxClasses)
    return "num_classes " + std::to_string(m.num_classes) + " outside [2, " + std::to_string(MaxClasses) + "]";
  for (int i = 0; i < m.num_classes; ++i)
    for (int j = i + 1; j < m.num_classes; ++j)
      if (m.labels[static_cast<std::size_t>(i)] == m.labels[static_cast<std::size_t>(j)])
        return "label " + std::to_string(m.labels[static_cast<std::size_t>(i)]) + " appears twice";
  if (m.kernel == SvmKernel::rbf && !(std::isfinite(m.gamma) && m.gamma > 0.0))
    return "gamma must be finite and > 0 for the RBF kernel";
  if constexpr (Dim == Eigen::Dynamic) {
    const auto d = m.input_mean.size();
    if (d < 1) return "dimension not set (input_mean is empty)";
    if (m.input_std.size() != d)
      return "input_std has " + std::to_string(m.input_std.size()) + " entries for dimension " + std::to_string(d);
    if (m.support_vectors.cols() != d)
      return "support vectors have " + std::to_string(m.support_vectors.cols()) + " features for dimension " +
             std::to_string(d);
  }
  if (!m.input_mean.allFinite()) return "input_mean contains NaN or Inf";
  if (!m.input_std.allFinite() || (m.input_std.array() <= 0.0).any()) return "input_std must be finite and > 0";
  const int machines = m.num_machines();
  if (m.support_vectors.rows() < 1) return "model has no support vectors";
  if (m.coefficients.rows() != machines)
    return "coefficients have " + std::to_string(m.coefficients.rows()) + " rows, expected " + std::to_string(machines);
  if (m.coefficients.cols() != m.support_vectors.rows())
    return "coefficients have " + std::to_string(m.coefficients.cols()) + " columns for " +
           std::to_string(m.support_vectors.rows()) + " support vectors";
  if (!m.support_vectors.allFinite()) return "support vectors contain NaN or Inf";
  if (!m.coefficients.allFinite()) return "coefficients contain NaN or Inf";
  for (int p = 0; p < machines; ++p) {
    const auto i = static_cast<std::size_t>(p);
    if (!std::isfinite(m.rho[i])) return "rho of machine " + std::to_string(p) + " is not finite";
    if (m.has_probability && !(std::isfinite(m.prob_a[i]) && std::isfinite(m.prob_b[i])))
      return "Platt parameters of machine " + std::to_string(p) + " are not finite";
  }
  return {};
}

/// Validates a model assembled by hand or by a loader and computes its derived fields. A model
/// that svm_model_problem (its check) refuses is a setting error (core/error.hpp: throws
/// std::invalid_argument naming the problem; under -fno-exceptions, prints it and aborts).
template <int Dim, int MaxClasses>
void finalize_svm_model(SvmModel<Dim, MaxClasses>& m) {
  if (auto problem = svm_model_problem(m); !problem.empty()) ctxfuse::detail::invalid_setting("SVM model: " + problem);
  m.linear_weights.setZero(SvmModel<Dim, MaxClasses>::kMaxMachines, m.dimension());
  if (m.kernel == SvmKernel::linear)
    m.linear_weights.topRows(m.num_machines()) = m.coefficients * m.support_vectors;
}

}  // namespace ctxfuse::classify

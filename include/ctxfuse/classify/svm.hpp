// Support vector machine inference with the feature dimension fixed at compile time, or (Dim =
// Eigen::Dynamic) set by the model at run time.
//
// One representation covers every machine layout: a set of support vectors (stored
// structure-of-arrays, one contiguous column per feature) and a dense coefficient matrix with one
// row per binary machine, so machine m's decision value is
//     f_m(x) = sum_s coefficients(m, s) * K(x', sv_s) - rho_m,   x' = (x - input_mean) / input_std.
// A libsvm one-vs-one model becomes k(k-1)/2 rows (zero where a support vector takes no part in a
// pair); a one-vs-rest model becomes k rows over the union of the k machines' support vectors.
// The dense layout costs a few multiply-adds per zero but lets the RBF kernel be evaluated once
// per support vector, in vectorised blocks, whatever the class count.
//
// Decision values, votes, Platt probabilities and pairwise coupling follow libsvm 3.x
// (svm_predict_values / svm_predict_probability) operation for operation, so that a model loaded
// from an svm-train file reproduces libsvm's numbers (tests/classify_svm checks this).
//
// Prediction never allocates: outputs go into SvmPrediction's fixed arrays and the kernel values
// live in a fixed stack block. The RBF kernel loop is in svm_rbf.hpp (vectorised, with an AVX2
// variant picked at run time on x86-64).
//
// SvmModel<Eigen::Dynamic> takes its dimension from the file or the training data: one
// instantiation serves every feature count (the tool's commands, any CSV), at the price of a
// plain loop over the features (svm_detail::rbf_sums_runtime, no instruction-set variants) and a
// size check on every input (Problem::features_wrong_size). Pipelines that know their features
// use a fixed Dim.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>

#include "ctxfuse/core/error.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/classify/svm_rbf.hpp"

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

/// Output of one prediction, in caller-owned fixed storage.
template <int MaxClasses = 8>
struct SvmPrediction {
  static constexpr int kMaxMachines = svm_max_machines(MaxClasses);
  int label = 0;        // predicted class label
  int class_index = 0;  // its index in SvmModel::labels
  int num_classes = 0;
  int num_machines = 0;
  std::array<double, kMaxMachines> decision_values{};
  bool has_probabilities = false;
  std::array<double, MaxClasses> probabilities{};  // in SvmModel::labels order, sums to one
};

namespace svm_detail {

inline constexpr double kMinPairProbability = 1e-7;  // libsvm's min_prob clip before coupling

/// Platt sigmoid 1 / (1 + exp(a f + b)) in the form that never computes 1 - (something near 1).
inline double platt_probability(double decision_value, double a, double b) {
  const double fApB = decision_value * a + b;
  if (fApB >= 0.0) return std::exp(-fApB) / (1.0 + std::exp(-fApB));
  return 1.0 / (1.0 + std::exp(fApB));
}

/// Wu, Lin and Weng (2004) second method, as libsvm's multiclass_probability: minimise
/// p'Qp subject to sum p = 1 by cyclic coordinate updates that keep Qp and p'Qp current.
/// r(i, j) = P(class i | i or j), row-major k x k in `r`.
template <int MaxClasses>
void couple_pairwise(int k, const std::array<double, MaxClasses * MaxClasses>& r, double* p) {
  std::array<double, MaxClasses * MaxClasses> Q{};
  std::array<double, MaxClasses> Qp{};
  const auto at = [k](int i, int j) { return static_cast<std::size_t>(i * k + j); };
  const int max_iter = std::max(100, k);
  const double eps = 0.005 / k;
  for (int t = 0; t < k; ++t) {
    p[t] = 1.0 / k;
    Q[at(t, t)] = 0.0;
    for (int j = 0; j < t; ++j) {
      Q[at(t, t)] += r[at(j, t)] * r[at(j, t)];
      Q[at(t, j)] = Q[at(j, t)];
    }
    for (int j = t + 1; j < k; ++j) {
      Q[at(t, t)] += r[at(j, t)] * r[at(j, t)];
      Q[at(t, j)] = -r[at(j, t)] * r[at(t, j)];
    }
  }
  for (int iter = 0; iter < max_iter; ++iter) {
    // Qp and p'Qp are recomputed from scratch each sweep: the running updates drift.
    double pQp = 0.0;
    for (int t = 0; t < k; ++t) {
      Qp[static_cast<std::size_t>(t)] = 0.0;
      for (int j = 0; j < k; ++j) Qp[static_cast<std::size_t>(t)] += Q[at(t, j)] * p[j];
      pQp += p[t] * Qp[static_cast<std::size_t>(t)];
    }
    double max_error = 0.0;
    for (int t = 0; t < k; ++t) max_error = std::max(max_error, std::fabs(Qp[static_cast<std::size_t>(t)] - pQp));
    if (max_error < eps) break;
    for (int t = 0; t < k; ++t) {
      const double diff = (-Qp[static_cast<std::size_t>(t)] + pQp) / Q[at(t, t)];
      p[t] += diff;
      pQp = (pQp + diff * (diff * Q[at(t, t)] + 2.0 * Qp[static_cast<std::size_t>(t)])) / (1.0 + diff) / (1.0 + diff);
      for (int j = 0; j < k; ++j) {
        Qp[static_cast<std::size_t>(j)] = (Qp[static_cast<std::size_t>(j)] + diff * Q[at(t, j)]) / (1.0 + diff);
        p[j] /= (1.0 + diff);
      }
    }
  }
}

/// sum_s coefficients(m, s) exp(-gamma |xs - sv_s|^2) for every machine, block by block so the
/// kernel values stay in a fixed stack buffer. The last, partial block is copied into a
/// zero-padded buffer so that the vectorised kernel loop always has its full fixed length.
template <int Dim, int MaxClasses>
void rbf_sums(const SvmModel<Dim, MaxClasses>& model, const Eigen::Matrix<double, Dim, 1>& xs, int machines,
              double* sums) {
  constexpr Eigen::Index block = kRbfBlock;
  using BlockArray = Eigen::Array<double, kRbfBlock, 1>;
  std::array<double, Dim> x{};
  for (int f = 0; f < Dim; ++f) x[static_cast<std::size_t>(f)] = xs[f];
  const Eigen::Index n = model.support_vectors.rows();
  const RbfExp exp_constants = rbf_exp_constants(model.gamma);
  const bool single = machines == 1;
  // Single machine: per-lane partial sums, added up once. Several machines: kernel values,
  // then one dot product per machine.
  BlockArray work = BlockArray::Zero();
  BlockArray padded_coef;
  Eigen::Array<double, kRbfBlock, Dim> tail;
  std::array<const double*, Dim> columns{};
  for (Eigen::Index start = 0; start < n; start += block) {
    const Eigen::Index len = std::min(block, n - start);
    const double* coef = model.coefficients.row(0).data() + start;
    if (len == block) {
      for (int f = 0; f < Dim; ++f) columns[static_cast<std::size_t>(f)] = model.support_vectors.col(f).data() + start;
    } else {
      tail.setZero();
      tail.topRows(len) = model.support_vectors.middleRows(start, len).array();
      for (int f = 0; f < Dim; ++f) columns[static_cast<std::size_t>(f)] = tail.col(f).data();
      if (single) {
        padded_coef.setZero();
        padded_coef.head(len) = model.coefficients.row(0).segment(start, len).transpose().array();
        coef = padded_coef.data();
      }
    }
    if (single) {
      rbf_block_dispatch<Dim, true>(columns, x, exp_constants, work.data(), coef);
    } else {
      rbf_block_dispatch<Dim, false>(columns, x, exp_constants, work.data(), nullptr);
      for (int m = 0; m < machines; ++m)
        sums[m] += model.coefficients.row(m).segment(start, len).dot(work.head(len).matrix().transpose());
    }
  }
  if (single) sums[0] = work.sum();
}

/// The kernel sums of every machine for a run-time dimension: x standardised feature by feature
/// on the fly, squared distances of a block of support vectors accumulated one feature column
/// at a time (contiguous loads), then the same exponential as the fixed-size kernel
/// (exp_neg_gamma, clamped at 708 / gamma). No instruction-set variants, no allocation.
template <int MaxClasses>
void rbf_sums_runtime(const SvmModel<Eigen::Dynamic, MaxClasses>& model, const Eigen::VectorXd& x, int machines,
                      double* sums) {
  const Eigen::Index dim = model.dimension();
  const Eigen::Index n = model.support_vectors.rows();
  const RbfExp e = rbf_exp_constants(model.gamma);
  std::array<double, kRbfBlock> k{};  // squared distances, then kernel values
  for (Eigen::Index start = 0; start < n; start += kRbfBlock) {
    const auto len = static_cast<std::size_t>(std::min<Eigen::Index>(kRbfBlock, n - start));
    std::fill_n(k.begin(), len, 0.0);
    for (Eigen::Index f = 0; f < dim; ++f) {
      const double xs = (x[f] - model.input_mean[f]) / model.input_std[f];
      const double* column = model.support_vectors.col(f).data() + start;
      for (std::size_t i = 0; i < len; ++i) {
        const double d = column[i] - xs;
        k[i] += d * d;
      }
    }
    for (std::size_t i = 0; i < len; ++i) k[i] = exp_neg_gamma(k[i] < e.d2_max ? k[i] : e.d2_max, e);
    for (int m = 0; m < machines; ++m) {
      const double* coef = model.coefficients.row(m).data() + start;
      double sum = 0.0;
      for (std::size_t i = 0; i < len; ++i) sum += coef[i] * k[i];
      sums[m] += sum;
    }
  }
}

/// Linear-kernel decision sums for a run-time dimension, x standardised on the fly.
template <int MaxClasses>
void linear_sums_runtime(const SvmModel<Eigen::Dynamic, MaxClasses>& model, const Eigen::VectorXd& x, int machines,
                         double* sums) {
  for (int m = 0; m < machines; ++m) {
    double sum = 0.0;
    for (Eigen::Index f = 0; f < model.dimension(); ++f)
      sum += model.linear_weights(m, f) * ((x[f] - model.input_mean[f]) / model.input_std[f]);
    sums[m] = sum;
  }
}

}  // namespace svm_detail

/// x' = (x - input_mean) / input_std, the transform the support vectors live in (for a
/// run-time dimension, x must have the model's; this allocates the result).
template <int Dim, int MaxClasses>
Eigen::Matrix<double, Dim, 1> svm_standardize(const SvmModel<Dim, MaxClasses>& model,
                                              const Eigen::Matrix<double, Dim, 1>& x) {
  return (x - model.input_mean).cwiseQuotient(model.input_std);
}

namespace svm_detail {

/// The input checks of svm_decision and svm_predict (also used by svm_fast_rbf.hpp).
template <int Dim>
Status input_status(const Eigen::Matrix<double, Dim, 1>& x) {
  if (!x.allFinite()) return Status::invalid(Problem::non_finite_features);
  if (x.cwiseAbs().maxCoeff() > 1e150) return Status::invalid(Problem::feature_magnitude);
  return {};
}

/// From the kernel sums of every machine: decision values sums - rho and the label by vote
/// (one-vs-one, ties to the lower class index, as libsvm) or by the largest decision value
/// (one-vs-rest). Shared by svm_decision and the fast evaluator of svm_fast_rbf.hpp.
template <int Dim, int MaxClasses>
void finish_decision(const SvmModel<Dim, MaxClasses>& model, const double* sums, SvmPrediction<MaxClasses>& out) {
  const int machines = model.num_machines();
  out.num_classes = model.num_classes;
  out.num_machines = machines;
  out.has_probabilities = false;
  for (int m = 0; m < machines; ++m) {
    const auto i = static_cast<std::size_t>(m);
    out.decision_values[i] = sums[i] - model.rho[i];
  }
  int winner = 0;
  if (model.num_classes == 2) {
    winner = out.decision_values[0] > 0.0 ? 0 : 1;
  } else if (model.multiclass == SvmMulticlass::one_vs_one) {
    std::array<int, MaxClasses> votes{};
    int p = 0;
    for (int i = 0; i < model.num_classes; ++i)
      for (int j = i + 1; j < model.num_classes; ++j, ++p)
        ++votes[static_cast<std::size_t>(out.decision_values[static_cast<std::size_t>(p)] > 0.0 ? i : j)];
    for (int i = 1; i < model.num_classes; ++i)
      if (votes[static_cast<std::size_t>(i)] > votes[static_cast<std::size_t>(winner)]) winner = i;
  } else {
    for (int i = 1; i < model.num_classes; ++i)
      if (out.decision_values[static_cast<std::size_t>(i)] > out.decision_values[static_cast<std::size_t>(winner)])
        winner = i;
  }
  out.class_index = winner;
  out.label = model.labels[static_cast<std::size_t>(winner)];
}

/// Adds the probabilities of svm_predict to a prediction filled by finish_decision (the model
/// has Platt parameters); the label becomes their argmax.
template <int Dim, int MaxClasses>
void add_probabilities(const SvmModel<Dim, MaxClasses>& model, SvmPrediction<MaxClasses>& out) {
  const int k = model.num_classes;
  const auto clip = [](double p) {
    return std::min(std::max(p, svm_detail::kMinPairProbability), 1.0 - svm_detail::kMinPairProbability);
  };
  const auto sigmoid = [&](int m) {
    const auto i = static_cast<std::size_t>(m);
    return clip(svm_detail::platt_probability(out.decision_values[i], model.prob_a[i], model.prob_b[i]));
  };
  if (k == 2) {
    out.probabilities[0] = sigmoid(0);
    out.probabilities[1] = 1.0 - out.probabilities[0];
  } else if (model.multiclass == SvmMulticlass::one_vs_one) {
    std::array<double, MaxClasses * MaxClasses> r{};
    int p = 0;
    for (int i = 0; i < k; ++i)
      for (int j = i + 1; j < k; ++j, ++p) {
        r[static_cast<std::size_t>(i * k + j)] = sigmoid(p);
        r[static_cast<std::size_t>(j * k + i)] = 1.0 - r[static_cast<std::size_t>(i * k + j)];
      }
    svm_detail::couple_pairwise<MaxClasses>(k, r, out.probabilities.data());
  } else {
    double total = 0.0;
    for (int m = 0; m < k; ++m) total += out.probabilities[static_cast<std::size_t>(m)] = sigmoid(m);
    for (int m = 0; m < k; ++m) out.probabilities[static_cast<std::size_t>(m)] /= total;
  }
  int best = 0;
  for (int i = 1; i < k; ++i)
    if (out.probabilities[static_cast<std::size_t>(i)] > out.probabilities[static_cast<std::size_t>(best)]) best = i;
  out.class_index = best;
  out.label = model.labels[static_cast<std::size_t>(best)];
  out.has_probabilities = true;
}

}  // namespace svm_detail

/// Decision values of every machine into out.decision_values, and the label by vote (one-vs-one,
/// ties to the lower class index, as libsvm) or by the largest decision value (one-vs-rest).
/// Returns accepted, or refuses a feature vector with NaN/Inf (Problem::non_finite_features), a
/// feature above 1e150 (Problem::feature_magnitude) or, for a run-time dimension, a length other
/// than the model's (Problem::features_wrong_size); on a refusal `out` is left untouched.
template <int Dim, int MaxClasses>
Status svm_decision(const SvmModel<Dim, MaxClasses>& model, const Eigen::Matrix<double, Dim, 1>& x,
                    SvmPrediction<MaxClasses>& out) {
  const int machines = model.num_machines();
  std::array<double, SvmModel<Dim, MaxClasses>::kMaxMachines> sums{};
  if constexpr (Dim == Eigen::Dynamic) {
    if (x.size() != model.dimension()) return Status::invalid(Problem::features_wrong_size);
    if (const Status status = svm_detail::input_status(x); !status) return status;
    if (model.kernel == SvmKernel::linear) {
      svm_detail::linear_sums_runtime(model, x, machines, sums.data());
    } else {
      svm_detail::rbf_sums_runtime(model, x, machines, sums.data());
    }
  } else {
    if (const Status status = svm_detail::input_status(x); !status) return status;
    const Eigen::Matrix<double, Dim, 1> xs = svm_standardize(model, x);
    if (model.kernel == SvmKernel::linear) {
      for (int m = 0; m < machines; ++m) sums[static_cast<std::size_t>(m)] = model.linear_weights.row(m).dot(xs);
    } else {
      svm_detail::rbf_sums(model, xs, machines, sums.data());
    }
  }
  svm_detail::finish_decision(model, sums.data(), out);
  return {};
}

/// Decision values plus, when the model has Platt parameters, class probabilities:
///  - two classes: the clipped sigmoid of the single machine (libsvm's binary case);
///  - one-vs-one: clipped pairwise sigmoids coupled by Wu-Lin-Weng's second method;
///  - one-vs-rest: each machine's clipped sigmoid P(class m | x) divided by their sum, a common
///    heuristic since k independent machines give no joint model.
/// With probabilities the label is their argmax (first on ties), as svm_predict_probability.
/// Refuses bad input as svm_decision does.
template <int Dim, int MaxClasses>
Status svm_predict(const SvmModel<Dim, MaxClasses>& model, const Eigen::Matrix<double, Dim, 1>& x,
                   SvmPrediction<MaxClasses>& out) {
  const Status status = svm_decision(model, x, out);
  if (!status || !model.has_probability) return status;
  svm_detail::add_probabilities(model, out);
  return {};
}

}  // namespace ctxfuse::classify

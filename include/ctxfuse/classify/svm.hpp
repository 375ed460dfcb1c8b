// Support vector machine inference on an SvmModel (svm_model.hpp), whose feature dimension is
// fixed at compile time or (Dim = Eigen::Dynamic) set at run time.
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

#include "ctxfuse/core/status.hpp"
#include "ctxfuse/classify/svm_model.hpp"
#include "ctxfuse/classify/svm_rbf.hpp"

namespace ctxfuse::classify {

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

// Training SVMs through libsvm (C-SVC), with the input standardisation fitted on the training
// data, one-vs-one (libsvm's own) or one-vs-rest (k binary libsvm machines) layouts, stratified
// k-fold cross-validation and a particle-swarm search over (log2 C, log2 gamma); those two are in
// svm_tune.hpp, included at the end.
//
// This is the only ctxfuse header that includes <svm.h>; link LibSVM::LibSVM to use it.
// Training allocates freely. libsvm draws random numbers from rand() (probability fitting and
// its internal shuffles); every call into svm_train here is preceded by srand(seed), so results
// are reproducible, at the price of resetting the process-wide rand() state. libsvm's progress
// output is silenced (a process-wide setting too).
#pragma once

#include <svm.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <memory>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_folds.hpp"
#include "ctxfuse/classify/svm_options.hpp"

namespace ctxfuse::classify {


/// Features as rows of an N x Dim matrix, labels one per row. Every function here also takes
/// Dim = Eigen::Dynamic (the dimension is then the matrix's column count; the model is an
/// SvmModel<Eigen::Dynamic>): one instantiation for any feature count.
template <int Dim>
using SvmFeatures = Eigen::Matrix<double, Eigen::Dynamic, Dim>;

namespace svm_train_detail {

inline void silent_print(const char*) {}

struct ModelDeleter {
  void operator()(svm_model* m) const { svm_free_and_destroy_model(&m); }
};
using ModelPtr = std::unique_ptr<svm_model, ModelDeleter>;

/// libsvm's dense problem: every feature written out (zeros included) so that indices line up.
template <int Dim>
struct Problem {
  std::vector<svm_node> nodes;
  std::vector<svm_node*> rows;
  std::vector<double> y;
  svm_problem prob{};
  Problem(const SvmFeatures<Dim>& x, std::span<const double> targets)
      : nodes(static_cast<std::size_t>(x.rows()) * static_cast<std::size_t>(x.cols() + 1)) {
    const auto n = static_cast<std::size_t>(x.rows());
    const auto dim = static_cast<int>(x.cols());
    rows.resize(n);
    y.assign(targets.begin(), targets.end());
    for (std::size_t i = 0; i < n; ++i) {
      svm_node* row = &nodes[i * static_cast<std::size_t>(dim + 1)];
      for (int f = 0; f < dim; ++f) row[f] = svm_node{f + 1, x(static_cast<Eigen::Index>(i), f)};
      row[dim] = svm_node{-1, 0.0};
      rows[i] = row;
    }
    prob.l = static_cast<int>(n);
    prob.y = y.data();
    prob.x = rows.data();
  }
  Problem(const Problem&) = delete;
  Problem& operator=(const Problem&) = delete;
};

inline svm_parameter make_parameter(const SvmTrainOptions& o, double gamma, std::vector<int>& weight_labels,
                                    std::vector<double>& weights) {
  svm_parameter p{};
  p.svm_type = C_SVC;
  p.kernel_type = o.kernel == SvmKernel::linear ? LINEAR : RBF;
  p.degree = 3;
  p.gamma = gamma;
  p.coef0 = 0.0;
  p.cache_size = o.cache_mb;
  p.eps = o.tolerance;
  p.C = o.C;
  p.nr_weight = static_cast<int>(weights.size());
  p.weight_label = weight_labels.empty() ? nullptr : weight_labels.data();
  p.weight = weights.empty() ? nullptr : weights.data();
  p.nu = 0.5;
  p.p = 0.1;
  p.shrinking = o.shrinking ? 1 : 0;
  p.probability = o.probability ? 1 : 0;
  return p;
}

inline ModelPtr run_libsvm(const svm_problem& prob, const svm_parameter& param, std::uint32_t seed) {
  svm_set_print_string_function(&silent_print);
  if (const char* problem = svm_check_parameter(&prob, &param)) throw std::invalid_argument(std::string("libsvm: ") + problem);
  std::srand(seed);
  return ModelPtr(svm_train(&prob, &param));
}

template <int Dim>
Eigen::Matrix<double, 1, Dim> sv_row(const svm_node* node, int dim) {
  Eigen::Matrix<double, 1, Dim> row = Eigen::Matrix<double, 1, Dim>::Zero(dim);
  for (; node->index != -1; ++node) {
    if (node->index < 1 || node->index > dim) throw std::invalid_argument("libsvm model: feature index " + std::to_string(node->index) + " outside [1, " + std::to_string(dim) + "]");
    row[node->index - 1] = node->value;
  }
  return row;
}

/// Largest feature index of a libsvm model's support vectors (at least 1).
inline int largest_index(const svm_model& lm) {
  int largest = 1;
  for (int s = 0; s < lm.l; ++s)
    for (const svm_node* node = lm.SV[s]; node->index != -1; ++node) largest = std::max(largest, node->index);
  return largest;
}

}  // namespace svm_train_detail

/// Converts a trained (or svm_load_model-ed) libsvm C-SVC model with a linear or RBF kernel.
/// The standardisation is identity; the caller may set it afterwards and re-finalise.
/// dimension: Dim; for Eigen::Dynamic 0 (the largest feature index) or the caller's.
template <int Dim, int MaxClasses = 8>
SvmModel<Dim, MaxClasses> svm_model_from_libsvm(const svm_model& lm, int dimension = Dim == Eigen::Dynamic ? 0 : Dim) {
  if (Dim != Eigen::Dynamic && dimension != Dim) throw std::invalid_argument("libsvm model: dimension differs from the model type's");
  const int dim = dimension > 0 ? dimension : svm_train_detail::largest_index(lm);
  if (lm.param.svm_type != C_SVC) throw std::invalid_argument("libsvm model: only C-SVC is supported");
  if (lm.param.kernel_type != LINEAR && lm.param.kernel_type != RBF)
    throw std::invalid_argument("libsvm model: only linear and RBF kernels are supported");
  const int k = lm.nr_class;
  if (k < 2 || k > MaxClasses) throw std::invalid_argument("libsvm model: class count " + std::to_string(k) + " outside [2, MaxClasses]");
  SvmModel<Dim, MaxClasses> m;
  m.kernel = lm.param.kernel_type == LINEAR ? SvmKernel::linear : SvmKernel::rbf;
  m.multiclass = SvmMulticlass::one_vs_one;
  m.gamma = m.kernel == SvmKernel::rbf ? lm.param.gamma : 1.0 / dim;
  m.input_mean.setZero(dim);
  m.input_std.setOnes(dim);
  m.num_classes = k;
  for (int i = 0; i < k; ++i) m.labels[static_cast<std::size_t>(i)] = lm.label[i];
  const int machines = svm_machine_count(SvmMulticlass::one_vs_one, k);
  for (int p = 0; p < machines; ++p) m.rho[static_cast<std::size_t>(p)] = lm.rho[p];
  m.has_probability = lm.probA != nullptr && lm.probB != nullptr;
  if (m.has_probability)
    for (int p = 0; p < machines; ++p) {
      m.prob_a[static_cast<std::size_t>(p)] = lm.probA[p];
      m.prob_b[static_cast<std::size_t>(p)] = lm.probB[p];
    }
  const Eigen::Index l = lm.l;
  m.support_vectors.resize(l, dim);
  for (Eigen::Index s = 0; s < l; ++s) m.support_vectors.row(s) = svm_train_detail::sv_row<Dim>(lm.SV[s], dim);
  m.coefficients.setZero(machines, l);
  std::vector<Eigen::Index> start(static_cast<std::size_t>(k), 0);
  for (int c = 1; c < k; ++c) start[static_cast<std::size_t>(c)] = start[static_cast<std::size_t>(c - 1)] + lm.nSV[c - 1];
  int p = 0;
  for (int i = 0; i < k; ++i)
    for (int j = i + 1; j < k; ++j, ++p) {
      for (int s = 0; s < lm.nSV[i]; ++s) {
        const auto col = start[static_cast<std::size_t>(i)] + s;
        m.coefficients(p, col) = lm.sv_coef[j - 1][col];
      }
      for (int s = 0; s < lm.nSV[j]; ++s) {
        const auto col = start[static_cast<std::size_t>(j)] + s;
        m.coefficients(p, col) = lm.sv_coef[i][col];
      }
    }
  finalize_svm_model(m);
  return m;
}

/// Per-feature mean and population standard deviation (std 1 where a feature is constant).
template <int Dim>
std::pair<Eigen::Matrix<double, Dim, 1>, Eigen::Matrix<double, Dim, 1>> fit_standardization(const SvmFeatures<Dim>& x) {
  Eigen::Matrix<double, Dim, 1> mean = x.colwise().mean().transpose();
  Eigen::Matrix<double, Dim, 1> std_dev =
      ((x.rowwise() - mean.transpose()).array().square().colwise().sum() / static_cast<double>(x.rows())).sqrt().transpose();
  for (Eigen::Index f = 0; f < x.cols(); ++f)
    if (!(std_dev[f] > 1e-300)) std_dev[f] = 1.0;
  return {mean, std_dev};
}

/// Trains a model. Throws std::invalid_argument for unusable data or options (sizes differ,
/// NaN/Inf features, fewer than two or more than MaxClasses classes, C <= 0, ...).
template <int Dim, int MaxClasses = 8>
SvmModel<Dim, MaxClasses> train_svm(const SvmFeatures<Dim>& x, std::span<const int> y, const SvmTrainOptions& options) {
  using namespace svm_train_detail;
  if (static_cast<std::size_t>(x.rows()) != y.size())
    throw std::invalid_argument("train_svm: " + std::to_string(x.rows()) + " feature rows but " + std::to_string(y.size()) + " labels");
  if (!x.allFinite()) throw std::invalid_argument("train_svm: features contain NaN or Inf");
  if (!(std::isfinite(options.C) && options.C > 0)) throw std::invalid_argument("train_svm: C must be finite and > 0");
  if (x.cols() < 1) throw std::invalid_argument("train_svm: no features");
  const auto dim = static_cast<int>(x.cols());
  const double gamma = options.gamma > 0 ? options.gamma : 1.0 / dim;
  if (!std::isfinite(gamma)) throw std::invalid_argument("train_svm: gamma must be finite");
  const auto classes = labels_in_order(y);
  if (classes.size() < 2 || classes.size() > static_cast<std::size_t>(MaxClasses))
    throw std::invalid_argument("train_svm: " + std::to_string(classes.size()) + " classes; need 2 to " + std::to_string(MaxClasses));

  Eigen::Matrix<double, Dim, 1> mean = Eigen::Matrix<double, Dim, 1>::Zero(dim);
  Eigen::Matrix<double, Dim, 1> std_dev = Eigen::Matrix<double, Dim, 1>::Ones(dim);
  if (options.standardize) std::tie(mean, std_dev) = fit_standardization<Dim>(x);
  const SvmFeatures<Dim> xs = ((x.rowwise() - mean.transpose()).array().rowwise() / std_dev.transpose().array()).matrix();

  std::vector<int> weight_labels;
  std::vector<double> weights;
  for (const auto& [label, w] : options.class_weights) {
    if (!(std::isfinite(w) && w > 0)) throw std::invalid_argument("train_svm: class weight of label " + std::to_string(label) + " must be > 0");
    weight_labels.push_back(label);
    weights.push_back(w);
  }

  SvmModel<Dim, MaxClasses> model;
  if (options.multiclass == SvmMulticlass::one_vs_one || classes.size() == 2) {
    std::vector<double> targets(y.begin(), y.end());
    Problem<Dim> problem(xs, targets);
    const auto param = make_parameter(options, gamma, weight_labels, weights);
    const ModelPtr lm = run_libsvm(problem.prob, param, options.seed);
    model = svm_model_from_libsvm<Dim, MaxClasses>(*lm, dim);
  } else {
    // Machine m: class m (+1) against all others (-1); oriented so that f_m > 0 means class m.
    const int k = static_cast<int>(classes.size());
    model.kernel = options.kernel;
    model.gamma = gamma;
    model.num_classes = k;
    model.has_probability = options.probability;
    std::map<int, Eigen::Index> column_of_sample;  // training row -> support vector column
    std::vector<std::vector<std::pair<int, double>>> machine_coefs(static_cast<std::size_t>(k));
    for (int m = 0; m < k; ++m) {
      const int positive = classes[static_cast<std::size_t>(m)];
      model.labels[static_cast<std::size_t>(m)] = positive;
      std::vector<double> targets(y.size());
      for (std::size_t i = 0; i < y.size(); ++i) targets[i] = y[i] == positive ? 1.0 : -1.0;
      // Class weights carry over to the positive side of each machine.
      std::vector<int> wl;
      std::vector<double> wv;
      for (const auto& [label, w] : options.class_weights)
        if (label == positive) {
          wl.push_back(1);
          wv.push_back(w);
        }
      Problem<Dim> problem(xs, targets);
      const auto param = make_parameter(options, gamma, wl, wv);
      const ModelPtr lm = run_libsvm(problem.prob, param, options.seed);
      const double sign = lm->label[0] == 1 ? 1.0 : -1.0;
      const auto mi = static_cast<std::size_t>(m);
      model.rho[mi] = sign * lm->rho[0];
      if (options.probability) {
        model.prob_a[mi] = lm->probA[0];
        model.prob_b[mi] = sign * lm->probB[0];
      }
      for (int s = 0; s < lm->l; ++s) {
        const int sample = lm->sv_indices[s] - 1;  // 1-based in libsvm
        column_of_sample.try_emplace(sample, static_cast<Eigen::Index>(column_of_sample.size()));
        machine_coefs[mi].emplace_back(sample, sign * lm->sv_coef[0][s]);
      }
    }
    const auto l = static_cast<Eigen::Index>(column_of_sample.size());
    model.support_vectors.resize(l, dim);
    for (const auto& [sample, col] : column_of_sample) model.support_vectors.row(col) = xs.row(sample);
    model.coefficients.setZero(k, l);
    for (int m = 0; m < k; ++m)
      for (const auto& [sample, c] : machine_coefs[static_cast<std::size_t>(m)]) model.coefficients(m, column_of_sample.at(sample)) = c;
  }
  model.multiclass = options.multiclass;
  model.input_mean = mean;
  model.input_std = std_dev;
  finalize_svm_model(model);
  return model;
}

}  // namespace ctxfuse::classify

// Cross-validation and the parameter search (they need train_svm above).
#include "ctxfuse/classify/svm_tune.hpp"

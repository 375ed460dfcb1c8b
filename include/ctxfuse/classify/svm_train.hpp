// Training SVMs through libsvm (C-SVC), with the input standardisation fitted on the training
// data, one-vs-one (libsvm's own) or one-vs-rest (k binary libsvm machines) layouts, stratified
// k-fold cross-validation and a particle-swarm search over (log2 C, log2 gamma).
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

#include "ctxfuse/classify/pso.hpp"
#include "ctxfuse/classify/svm.hpp"

namespace ctxfuse::classify {

struct SvmTrainOptions {
  SvmKernel kernel = SvmKernel::rbf;
  SvmMulticlass multiclass = SvmMulticlass::one_vs_one;
  double C = 1.0;
  double gamma = 0.0;  // <= 0 means 1 / Dim (libsvm's default)
  bool probability = false;
  // Fit mean/std per feature on the training data and train in standardised units. Features
  // with zero spread keep std 1 so that they pass through unchanged.
  bool standardize = true;
  // Optional per-label multipliers of C (libsvm's -wi).
  std::vector<std::pair<int, double>> class_weights;
  double tolerance = 1e-3;  // libsvm -e
  double cache_mb = 200.0;
  bool shrinking = true;
  std::uint32_t seed = 1;  // srand() before each libsvm call
};

/// Features as rows of an N x Dim matrix, labels one per row.
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
  Problem(const SvmFeatures<Dim>& x, std::span<const double> targets) : nodes(static_cast<std::size_t>(x.rows()) * (Dim + 1)) {
    const auto n = static_cast<std::size_t>(x.rows());
    rows.resize(n);
    y.assign(targets.begin(), targets.end());
    for (std::size_t i = 0; i < n; ++i) {
      svm_node* row = &nodes[i * (Dim + 1)];
      for (int f = 0; f < Dim; ++f) row[f] = svm_node{f + 1, x(static_cast<Eigen::Index>(i), f)};
      row[Dim] = svm_node{-1, 0.0};
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
Eigen::Matrix<double, 1, Dim> sv_row(const svm_node* node) {
  Eigen::Matrix<double, 1, Dim> row = Eigen::Matrix<double, 1, Dim>::Zero();
  for (; node->index != -1; ++node) {
    if (node->index < 1 || node->index > Dim) throw std::invalid_argument("libsvm model: feature index " + std::to_string(node->index) + " outside [1, " + std::to_string(Dim) + "]");
    row[node->index - 1] = node->value;
  }
  return row;
}

}  // namespace svm_train_detail

/// Converts a trained (or svm_load_model-ed) libsvm C-SVC model with a linear or RBF kernel.
/// The standardisation is identity; the caller may set it afterwards and re-finalise.
template <int Dim, int MaxClasses = 8>
SvmModel<Dim, MaxClasses> svm_model_from_libsvm(const svm_model& lm) {
  if (lm.param.svm_type != C_SVC) throw std::invalid_argument("libsvm model: only C-SVC is supported");
  if (lm.param.kernel_type != LINEAR && lm.param.kernel_type != RBF)
    throw std::invalid_argument("libsvm model: only linear and RBF kernels are supported");
  const int k = lm.nr_class;
  if (k < 2 || k > MaxClasses) throw std::invalid_argument("libsvm model: class count " + std::to_string(k) + " outside [2, MaxClasses]");
  SvmModel<Dim, MaxClasses> m;
  m.kernel = lm.param.kernel_type == LINEAR ? SvmKernel::linear : SvmKernel::rbf;
  m.multiclass = SvmMulticlass::one_vs_one;
  m.gamma = m.kernel == SvmKernel::rbf ? lm.param.gamma : 1.0 / Dim;
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
  m.support_vectors.resize(l, Dim);
  for (Eigen::Index s = 0; s < l; ++s) m.support_vectors.row(s) = svm_train_detail::sv_row<Dim>(lm.SV[s]);
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
  for (int f = 0; f < Dim; ++f)
    if (!(std_dev[f] > 1e-300)) std_dev[f] = 1.0;
  return {mean, std_dev};
}

/// Distinct labels in order of first appearance (libsvm's class order).
inline std::vector<int> labels_in_order(std::span<const int> y) {
  std::vector<int> out;
  for (int v : y)
    if (std::find(out.begin(), out.end(), v) == out.end()) out.push_back(v);
  return out;
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
  const double gamma = options.gamma > 0 ? options.gamma : 1.0 / Dim;
  if (!std::isfinite(gamma)) throw std::invalid_argument("train_svm: gamma must be finite");
  const auto classes = labels_in_order(y);
  if (classes.size() < 2 || classes.size() > static_cast<std::size_t>(MaxClasses))
    throw std::invalid_argument("train_svm: " + std::to_string(classes.size()) + " classes; need 2 to " + std::to_string(MaxClasses));

  Eigen::Matrix<double, Dim, 1> mean = Eigen::Matrix<double, Dim, 1>::Zero(), std_dev = Eigen::Matrix<double, Dim, 1>::Ones();
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
    model = svm_model_from_libsvm<Dim, MaxClasses>(*lm);
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
    model.support_vectors.resize(l, Dim);
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

/// Rows of x (and y) whose mask entry equals `keep`.
template <int Dim>
std::pair<SvmFeatures<Dim>, std::vector<int>> select_rows(const SvmFeatures<Dim>& x, std::span<const int> y,
                                                          const std::vector<int>& group, int wanted, bool equal) {
  std::vector<Eigen::Index> rows;
  for (std::size_t i = 0; i < group.size(); ++i)
    if ((group[i] == wanted) == equal) rows.push_back(static_cast<Eigen::Index>(i));
  SvmFeatures<Dim> out(static_cast<Eigen::Index>(rows.size()), Dim);
  std::vector<int> labels(rows.size());
  for (std::size_t r = 0; r < rows.size(); ++r) {
    out.row(static_cast<Eigen::Index>(r)) = x.row(rows[r]);
    labels[r] = y[static_cast<std::size_t>(rows[r])];
  }
  return {std::move(out), std::move(labels)};
}

struct SvmCrossValidation {
  double accuracy = 0.0;       // fraction of samples predicted right
  std::vector<int> predicted;  // out-of-fold prediction per sample
};

/// Stratified k-fold cross-validation; each fold's model (standardisation included) is fitted on
/// the other folds only.
template <int Dim, int MaxClasses = 8>
SvmCrossValidation cross_validate_svm(const SvmFeatures<Dim>& x, std::span<const int> y, const SvmTrainOptions& options,
                                      int folds, std::uint64_t seed) {
  if (static_cast<std::size_t>(x.rows()) != y.size()) throw std::invalid_argument("cross_validate_svm: sizes differ");
  const auto fold = stratified_folds(y, folds, seed);
  SvmCrossValidation result;
  result.predicted.assign(y.size(), 0);
  std::size_t correct = 0;
  for (int f = 0; f < folds; ++f) {
    auto [train_x, train_y] = select_rows<Dim>(x, y, fold, f, false);
    if (train_y.empty() || labels_in_order(train_y).size() < 2) continue;
    const auto model = train_svm<Dim, MaxClasses>(train_x, train_y, options);
    SvmPrediction<MaxClasses> out;
    for (std::size_t i = 0; i < y.size(); ++i) {
      if (fold[i] != f) continue;
      const Eigen::Matrix<double, Dim, 1> xi = x.row(static_cast<Eigen::Index>(i)).transpose();
      svm_predict(model, xi, out);
      result.predicted[i] = out.label;
      correct += out.label == y[i] ? 1 : 0;
    }
  }
  result.accuracy = y.empty() ? 0.0 : static_cast<double>(correct) / static_cast<double>(y.size());
  return result;
}

struct SvmTuneOptions {
  // Search box in log2 units, the usual libsvm grid.py range.
  double log2_c_min = -5.0, log2_c_max = 15.0;
  double log2_gamma_min = -15.0, log2_gamma_max = 3.0;
  int folds = 5;
  std::uint64_t fold_seed = 1;
  PsoOptions pso{.swarm_size = 10, .iterations = 10};
};

struct SvmTuneResult {
  double C = 1.0;
  double gamma = 0.0;       // 0 for the linear kernel
  double cv_accuracy = 0.0;  // best cross-validated accuracy found
  int evaluations = 0;      // cross-validations run
};

/// PSO over (log2 C, log2 gamma) (log2 C only for the linear kernel) maximising stratified
/// k-fold accuracy, as the region-recognition paper tunes its SVM. Probability fitting is off
/// during the search (it does not change the labels' decision function much and costs 5x).
template <int Dim, int MaxClasses = 8>
SvmTuneResult tune_svm_pso(const SvmFeatures<Dim>& x, std::span<const int> y, SvmTrainOptions base,
                           const SvmTuneOptions& tune = {}) {
  base.probability = false;
  SvmTuneResult result;
  if (base.kernel == SvmKernel::linear) {
    const auto objective = [&](const Eigen::Matrix<double, 1, 1>& p) {
      SvmTrainOptions o = base;
      o.C = std::exp2(p[0]);
      return cross_validate_svm<Dim, MaxClasses>(x, y, o, tune.folds, tune.fold_seed).accuracy;
    };
    const auto r = pso_maximize<1>(objective, Eigen::Matrix<double, 1, 1>(tune.log2_c_min),
                                   Eigen::Matrix<double, 1, 1>(tune.log2_c_max), tune.pso);
    result.C = std::exp2(r.best_position[0]);
    result.cv_accuracy = r.best_value;
    result.evaluations = r.evaluations;
  } else {
    const auto objective = [&](const Eigen::Vector2d& p) {
      SvmTrainOptions o = base;
      o.C = std::exp2(p[0]);
      o.gamma = std::exp2(p[1]);
      return cross_validate_svm<Dim, MaxClasses>(x, y, o, tune.folds, tune.fold_seed).accuracy;
    };
    const auto r = pso_maximize<2>(objective, Eigen::Vector2d(tune.log2_c_min, tune.log2_gamma_min),
                                   Eigen::Vector2d(tune.log2_c_max, tune.log2_gamma_max), tune.pso);
    result.C = std::exp2(r.best_position[0]);
    result.gamma = std::exp2(r.best_position[1]);
    result.cv_accuracy = r.best_value;
    result.evaluations = r.evaluations;
  }
  return result;
}

}  // namespace ctxfuse::classify

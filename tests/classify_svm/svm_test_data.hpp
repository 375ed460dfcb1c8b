// Simulated labelled data shared by the SVM tests: Gaussian clusters, seeded.
#pragma once

#include <Eigen/Core>
#include <random>
#include <vector>

namespace ctxfuse::test {

struct LabelledSet {
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic> x;  // rows = samples
  std::vector<int> y;
};

/// `per_class` samples around each centre with per-feature standard deviation `spread`.
inline LabelledSet gaussian_clusters(const std::vector<std::vector<double>>& centres, const std::vector<int>& labels,
                                     int per_class, const std::vector<double>& spread, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  const auto dim = static_cast<Eigen::Index>(spread.size());
  LabelledSet s;
  s.x.resize(static_cast<Eigen::Index>(centres.size()) * per_class, dim);
  Eigen::Index row = 0;
  // Interleave the classes so that libsvm's first-appearance label order is the given order.
  for (int i = 0; i < per_class; ++i)
    for (std::size_t c = 0; c < centres.size(); ++c, ++row) {
      for (Eigen::Index f = 0; f < dim; ++f)
        s.x(row, f) = centres[c][static_cast<std::size_t>(f)] + spread[static_cast<std::size_t>(f)] * n01(rng);
      s.y.push_back(labels[c]);
    }
  return s;
}

}  // namespace ctxfuse::test

#include "ctxfuse/classify/svm.hpp"

namespace ctxfuse::test {

/// A syntactically valid model with random support vectors and coefficients (not a trained
/// one): enough for file round trips, allocation counting and closed-form checks.
template <int Dim, int MaxClasses = 8>
classify::SvmModel<Dim, MaxClasses> random_model(classify::SvmKernel kernel, classify::SvmMulticlass layout, int classes,
                                                 int support_vectors, bool probability, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  classify::SvmModel<Dim, MaxClasses> m;
  m.kernel = kernel;
  m.multiclass = layout;
  m.gamma = 0.8;
  m.num_classes = classes;
  for (int i = 0; i < classes; ++i) m.labels[static_cast<std::size_t>(i)] = 10 * i - 5;
  for (int f = 0; f < Dim; ++f) {
    m.input_mean[f] = 3.0 * u(rng);
    m.input_std[f] = 1.5 + u(rng);
  }
  const int machines = m.num_machines();
  m.support_vectors.resize(support_vectors, Dim);
  for (int s = 0; s < support_vectors; ++s)
    for (int f = 0; f < Dim; ++f) m.support_vectors(s, f) = 2.0 * u(rng);
  m.coefficients.resize(machines, support_vectors);
  for (int r = 0; r < machines; ++r)
    for (int s = 0; s < support_vectors; ++s) m.coefficients(r, s) = u(rng);
  for (int r = 0; r < machines; ++r) {
    m.rho[static_cast<std::size_t>(r)] = 0.3 * u(rng);
    m.prob_a[static_cast<std::size_t>(r)] = -1.0 - u(rng);
    m.prob_b[static_cast<std::size_t>(r)] = 0.2 * u(rng);
  }
  m.has_probability = probability;
  classify::finalize_svm_model(m);
  return m;
}

// A print function for libsvm's svm_set_print_string_function that prints nothing.
inline void quiet(const char*) {}

}  // namespace ctxfuse::test

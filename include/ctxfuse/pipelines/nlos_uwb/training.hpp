// Training p1's SVM (nlos_uwb/classifier.hpp) on labelled ranges of other recordings, through
// libsvm (classify/svm_train.hpp): a balanced, evenly thinned subsample, the RBF gamma by
// cross-validation over contiguous blocks. The one nlos_uwb header that needs libsvm.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "ctxfuse/classify/svm_folds.hpp"
#include "ctxfuse/classify/svm_train.hpp"
#include "ctxfuse/classify/svm_tune.hpp"
#include "ctxfuse/pipelines/nlos_uwb/classifier.hpp"
#include "ctxfuse/pipelines/nlos_uwb/settings.hpp"

namespace ctxfuse::pipelines::nlos_uwb {

/// Labelled SVM rows (from studies/nlos_uwb.hpp: runs on other recordings, residual labels).
struct LabelledSvmRows {
  std::vector<SvmInput> inputs;
  std::vector<int> labels;  // kNlosLabel / kLosLabel
};

/// The RBF gamma of the best cross-validated accuracy over libsvm's grid (log2 gamma = 3, 1,
/// ..., -15; C and the rest as `base`, no probabilities), folds of contiguous blocks within
/// each class of x's two class runs (the first `per_class` rows one class, the rest the other,
/// each in time order); ties go to the smaller gamma.
template <int Dim>
double cross_validated_gamma(const classify::SvmFeatures<Dim>& x, const std::vector<int>& y, std::size_t per_class, int folds,
                             classify::SvmTrainOptions base) {
  std::vector<int> fold = classify::block_folds(per_class, folds);
  const std::vector<int> second = classify::block_folds(y.size() - per_class, folds);
  fold.insert(fold.end(), second.begin(), second.end());
  base.probability = false;
  double best_gamma = 0.0, best = -1.0;
  for (int log2_gamma = 3; log2_gamma >= -15; log2_gamma -= 2) {
    base.gamma = std::ldexp(1.0, log2_gamma);
    const double score = classify::cross_validate_svm<Dim, 2>(x, y, base, fold).score;
    if (score >= best) {
      best = score;
      best_gamma = base.gamma;
    }
  }
  return best_gamma;
}

/// Trains an SVM (RBF, Platt probabilities) on `features(input)` (a Dim-vector) of a balanced
/// subsample: every NLOS row and as many LOS rows, both thinned evenly to at most
/// settings.svm_rows_per_class; rows whose SvmInput is not finite are skipped. gamma by
/// cross_validated_gamma when the settings ask for it and each class has a row per fold,
/// libsvm's default otherwise. Throws std::invalid_argument when a class is missing or the
/// rows are unusable.
template <int Dim, class Features>
classify::SvmModel<Dim, 2> train_balanced_svm(const LabelledSvmRows& rows, const Settings& s, Features features) {
  std::vector<std::size_t> nlos, los;
  for (std::size_t i = 0; i < rows.inputs.size(); ++i)
    if (rows.inputs[i].finite()) (rows.labels[i] == kNlosLabel ? nlos : los).push_back(i);
  if (nlos.empty() || los.empty()) throw std::invalid_argument("train_nlos_svm: both classes needed, got " +
                                                               std::to_string(nlos.size()) + " NLOS and " +
                                                               std::to_string(los.size()) + " LOS rows");
  const std::size_t per_class = std::min({nlos.size(), los.size(), static_cast<std::size_t>(s.svm_rows_per_class)});
  classify::SvmFeatures<Dim> x(static_cast<Eigen::Index>(2 * per_class), Dim);
  std::vector<int> y;
  y.reserve(2 * per_class);
  auto take = [&](const std::vector<std::size_t>& from, int label) {
    for (std::size_t k = 0; k < per_class; ++k) {
      const std::size_t i = from[k * from.size() / per_class];  // evenly spaced in time
      x.row(static_cast<Eigen::Index>(y.size())) = features(rows.inputs[i]).transpose();
      y.push_back(label);
    }
  };
  take(nlos, kNlosLabel);
  take(los, kLosLabel);
  classify::SvmTrainOptions o;
  if (s.svm_gamma_by_cross_validation && per_class >= static_cast<std::size_t>(s.svm_cv_folds))
    o.gamma = cross_validated_gamma<Dim>(x, y, per_class, s.svm_cv_folds, o);
  o.probability = true;
  return classify::train_svm<Dim, 2>(x, y, o);
}

/// Trains p1's SVM on (v_u, v_i) (train_balanced_svm).
template <class = void>
NlosSvm train_nlos_svm(const LabelledSvmRows& rows, const Settings& s) {
  return train_balanced_svm<2>(rows, s, [](const SvmInput& in) { return in.vector(); });
}

}  // namespace ctxfuse::pipelines::nlos_uwb

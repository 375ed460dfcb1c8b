// Per-range NLOS classification of the paper (eq. 1-8): SVM probability p1 on (v_u, v_i),
// consistency probability p2 from e = |d_rho| - d_d, Dempster-Shafer R = p1 p2 / (p1 p2 +
// q1 q2), NLOS when R > 0.8. Without an IMU the vehicle speed v_i and the travelled distance
// d_d come from the estimator's own velocity (the caller passes its speed).
//
// The SVM is trained on labelled ranges of other recordings (studies/nlos_uwb.hpp builds them;
// labels from residuals against those recordings' references), never on the run it scores.
// Without a model p1 is absent and R is p2 alone (D-S with one source). Training the SVM
// (libsvm) is in nlos_uwb/training.hpp: this header, the inference side, does not need libsvm.
// The model is evaluated through classify::SvmFastRbf, built once at construction (shared by
// copies of the classifier): its automatic choice takes the fast Gauss transform where it pays
// (many support vectors), the exact sum otherwise; probabilities equal the exact path's to 1e-9.
//
// Per-anchor state is a fixed table of kMaxAnchors slots filled on first sight of an anchor;
// an anchor beyond it gets no evidence (verdict NaN, LOS), never an allocation.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "ctxfuse/classify/consistency.hpp"
#include "ctxfuse/classify/dempster_shafer.hpp"
#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_fast_rbf.hpp"
#include "ctxfuse/features/nlos.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/pipelines/nlos_uwb/policies.hpp"
#include "ctxfuse/pipelines/nlos_uwb/settings.hpp"

namespace ctxfuse::pipelines::nlos_uwb {

using NlosSvm = classify::SvmModel<2, 2>;
using NlosSvmEvaluator = classify::SvmFastRbf<2, 2>;
inline constexpr int kNlosLabel = 1, kLosLabel = 0;

/// The SVM's input: range rate v_u [m/s] and vehicle speed v_i [m/s].
struct SvmInput {
  double range_rate_mps = std::nan("");
  double speed_mps = std::nan("");
  Eigen::Vector2d vector() const { return {range_rate_mps, speed_mps}; }
  bool finite() const { return std::isfinite(range_rate_mps) && std::isfinite(speed_mps); }
};

class NlosClassifier {
 public:
  static constexpr int kMaxAnchors = 16;

  explicit NlosClassifier(const Settings& s, const std::optional<NlosSvm>& svm = std::nullopt)
      : NlosClassifier(s, svm ? std::make_shared<const NlosSvmEvaluator>(*svm) : nullptr) {}

  /// With an evaluator built elsewhere (one build for many classifiers); nullptr: no SVM.
  NlosClassifier(const Settings& s, std::shared_ptr<const NlosSvmEvaluator> svm)
      : consistency_(s.consistency()), decision_{s.nlos_belief_threshold}, svm_(std::move(svm)), max_speed_(s.max_speed_mps),
        max_range_(s.max_range_m) {}

  bool has_svm() const { return svm_ != nullptr; }
  /// The SVM's evaluator (its plan() says whether the fast Gauss transform is used); nullptr: none.
  const NlosSvmEvaluator* svm() const { return svm_.get(); }

  /// Verdict on range r with the platform's current speed; `input` receives the SVM's features
  /// (NaN when the anchor has no previous range). Every range of the run must come through
  /// here, in time order, attached or not: v_u and d_rho are differences of consecutive ranges.
  RangeVerdict classify(const messages::UwbRange& r, double speed_mps, SvmInput* input = nullptr) {
    RangeVerdict v;
    features::NlosFeatureExtractor* x = extractor_of(r.anchor_id);
    if (!x) return v;
    features::NlosFeatures f;
    const features::UwbRangeSample sample{r.t, r.range_m, r.rssi_dbm, r.rssi_first_path_dbm};
    const double speed = std::isfinite(speed_mps) ? speed_mps : 0.0;
    if (!x->push(sample, speed, f) || !f.has_previous_sample) return v;
    const SvmInput in{f.range_rate_mps, f.vehicle_speed_mps};
    if (input) *input = in;
    v.p2 = consistency_.nlos_probability(f.consistency_error_m);
    if (svm_ && in.finite()) {
      classify::SvmPrediction<2> out;
      if (svm_->predict(Eigen::Vector2d(in.vector()), out).accepted() && out.has_probabilities)
        v.p1 = out.probabilities[svm_->model().labels[0] == kNlosLabel ? 0 : 1];
    }
    if (std::isnan(v.p1)) {
      v.R = v.p2;
    } else {
      const classify::DsResult ds = classify::combine_probabilities(v.p1, v.p2);
      // Total conflict (one source certain of each side) leaves no belief: no decision.
      v.R = ds.status.accepted() ? ds.nlos_belief() : std::nan("");
    }
    v.nlos = !std::isnan(v.R) && decision_(v.R);
    return v;
  }

 private:
  features::NlosFeatureExtractor* extractor_of(int anchor) {
    for (int i = 0; i < used_; ++i)
      if (ids_[static_cast<std::size_t>(i)] == anchor) return &extractors_[static_cast<std::size_t>(i)];
    if (used_ == kMaxAnchors) return nullptr;
    const auto i = static_cast<std::size_t>(used_++);
    ids_[i] = anchor;
    extractors_[i].max_speed_mps = max_speed_;
    extractors_[i].max_range_m = max_range_;
    return &extractors_[i];
  }

  classify::ConsistencyModel consistency_;
  classify::NlosDecisionRule decision_;
  std::shared_ptr<const NlosSvmEvaluator> svm_;
  double max_speed_, max_range_;
  std::array<int, kMaxAnchors> ids_{};
  std::array<features::NlosFeatureExtractor, kMaxAnchors> extractors_{};
  int used_ = 0;
};

}  // namespace ctxfuse::pipelines::nlos_uwb

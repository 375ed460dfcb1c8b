// The scene paper's classifier (digest section B) on simulated drives, for the GNSS/INS study
// (studies/gins_sim_study.hpp): the eight features per receiver epoch (features/gnss_scene.hpp),
// a linear one-vs-one SVM with Platt probabilities and pairwise coupling (classify/svm_train.hpp,
// C = 1, standardised inputs: the paper's choice, nothing searched), trained on drives of other
// seeds with their true scene labels (sim::Scene: open, obstructed, indoor) -- the seeds of
// studies/region_training.hpp -- and applied to the test drive's epochs, whose labels it never
// sees. Needs libsvm at link time (training), like the region recogniser.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_train.hpp"
#include "ctxfuse/studies/region_training.hpp"
#include "ctxfuse/features/gnss_scene.hpp"
#include "ctxfuse/policies/scene_noise.hpp"
#include "ctxfuse/sim/drive.hpp"

namespace ctxfuse::studies {

using SceneSvm = classify::SvmModel<features::kGnssSceneFeatureCount, 3>;

/// Features of every GNSS epoch of a drive, in order, and the true scene of each.
struct SceneSamples {
  std::vector<features::GnssSceneFeatures> x;
  std::vector<int> scene;
};

inline SceneSamples scene_samples(const sim::Drive& d) {
  SceneSamples out;
  features::GnssSceneExtractor<> extractor;
  std::vector<features::SatelliteObservation> sats;
  for (const auto& e : d.gnss) {
    sats.clear();
    for (const auto& s : d.satellites_of(e)) sats.push_back({s.sat_id, s.elevation_deg, s.azimuth_deg, s.cn0_dbhz});
    features::GnssEpoch epoch{e.t, sats, e.pdop < 0.0 ? std::numeric_limits<double>::quiet_NaN() : e.pdop};
    features::GnssSceneFeatures f;
    if (!extractor.push(epoch, f)) f.fill(-1.0);
    out.x.push_back(f);
    out.scene.push_back(static_cast<int>(e.scene));
  }
  return out;
}

/// The classifier for a test drive of configuration `test`: trained on the drives of seeds
/// test.seed + 101 .. + 103 (RegionTrainingDrives), true scene labels.
template <class = void>
SceneSvm train_scene_svm_for(const sim::DriveConfig& test) {
  std::vector<features::GnssSceneFeatures> rows;
  std::vector<int> labels;
  for (std::uint64_t k = 0; k < RegionTrainingDrives::train_drives; ++k) {
    sim::DriveConfig cfg = test;
    cfg.seed = test.seed + RegionTrainingDrives::train_seed_offset + k;
    const SceneSamples s = scene_samples(sim::simulate_drive(cfg));
    rows.insert(rows.end(), s.x.begin(), s.x.end());
    labels.insert(labels.end(), s.scene.begin(), s.scene.end());
  }
  classify::SvmFeatures<features::kGnssSceneFeatureCount> x(static_cast<Eigen::Index>(rows.size()), features::kGnssSceneFeatureCount);
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (int j = 0; j < features::kGnssSceneFeatureCount; ++j) x(static_cast<Eigen::Index>(i), j) = rows[i][static_cast<std::size_t>(j)];
  classify::SvmTrainOptions o;
  o.kernel = classify::SvmKernel::linear;
  o.probability = true;
  return classify::train_svm<features::kGnssSceneFeatureCount, 3>(x, labels, o);
}

/// Scene probabilities (open, obstructed, indoor) per epoch; a scene the model was not trained
/// on gets 0. An epoch the SVM cannot score gets NaN (the noise policy then refuses it).
template <class = void>
std::vector<policies::SceneProbabilities> scene_probabilities(const SceneSvm& svm, const SceneSamples& s) {
  std::vector<policies::SceneProbabilities> out;
  out.reserve(s.x.size());
  for (const auto& f : s.x) {
    Eigen::Matrix<double, features::kGnssSceneFeatureCount, 1> x;
    for (int j = 0; j < features::kGnssSceneFeatureCount; ++j) x(j) = f[static_cast<std::size_t>(j)];
    classify::SvmPrediction<3> pred;
    policies::SceneProbabilities p{};
    if (!classify::svm_predict(svm, x, pred) || !pred.has_probabilities) {
      p.fill(std::numeric_limits<double>::quiet_NaN());
    } else {
      for (int c = 0; c < svm.num_classes; ++c) {
        const int label = svm.labels[static_cast<std::size_t>(c)];
        if (label >= 0 && label < policies::kSceneClasses) p[static_cast<std::size_t>(label)] = pred.probabilities[static_cast<std::size_t>(c)];
      }
    }
    out.push_back(p);
  }
  return out;
}

/// One-hot probabilities from the true scenes (the oracle row of the study, not a result).
inline std::vector<policies::SceneProbabilities> true_scene_probabilities(const SceneSamples& s) {
  std::vector<policies::SceneProbabilities> out(s.scene.size(), policies::SceneProbabilities{});
  for (std::size_t i = 0; i < s.scene.size(); ++i) out[i][static_cast<std::size_t>(s.scene[i])] = 1.0;
  return out;
}

}  // namespace ctxfuse::studies

// The region paper's protocol on simulated drives: train, validate and test on separate data.
// For a test drive of seed N, the drives of seeds N + 101, N + 102 and N + 103 (same
// configuration otherwise) train the recogniser and seed N + 202 gives the per-region
// validation accuracies of the joint vote; labels come from each drive's truth. Three training
// drives: one drive's 540 epochs leave the SVM's (C, gamma) search free to fit that drive's
// particular sky (the PSO then runs to the edges of its box and the SVM generalises worse than
// the HMM). `ctxfuse demo` and `ctxfuse region-study` use it; `ctxfuse run region-imm` does the
// same from logs written by `ctxfuse sim` for those seeds.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "ctxfuse/eval/truth.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/pipelines/region_imm/training.hpp"
#include "ctxfuse/sim/drive.hpp"
#include "ctxfuse/sim/streams.hpp"

namespace ctxfuse::studies {

struct RegionTrainingDrives {
  static constexpr std::uint64_t train_seed_offset = 101, train_drives = 3, validate_seed_offset = 202;
};

/// A log's features labelled with the true region at each epoch.
inline pipelines::region_imm::LabelledFeatures labelled_features(const messages::SensorLog& log, const sim::TruthLog& truth) {
  pipelines::region_imm::LabelledFeatures out;
  out.features = pipelines::region_imm::gnss_features(log.sat_epochs);
  out.labels = eval::region_labels(truth.truth, out.features.t);
  return out;
}

inline pipelines::region_imm::LabelledFeatures labelled_features(const sim::Drive& d) {
  return labelled_features(sim::sensor_log(d), sim::truth_log(d));
}

/// The recogniser for a test drive of configuration `test` (its seed included), trained and
/// validated on the drives of RegionTrainingDrives.
template <class = void>
pipelines::region_imm::Recogniser train_recogniser_for(const sim::DriveConfig& test,
                                                         const pipelines::region_imm::RecogniserOptions& opts = {}) {
  std::vector<pipelines::region_imm::LabelledFeatures> train;
  for (std::uint64_t k = 0; k < RegionTrainingDrives::train_drives; ++k) {
    sim::DriveConfig cfg = test;
    cfg.seed = test.seed + RegionTrainingDrives::train_seed_offset + k;
    train.push_back(labelled_features(sim::simulate_drive(cfg)));
  }
  sim::DriveConfig validate = test;
  validate.seed = test.seed + RegionTrainingDrives::validate_seed_offset;
  return pipelines::region_imm::train_recogniser(std::span<const pipelines::region_imm::LabelledFeatures>(train),
                                                 labelled_features(sim::simulate_drive(validate)), opts);
}

}  // namespace ctxfuse::studies

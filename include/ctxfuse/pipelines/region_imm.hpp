// The region paper's whole pipeline (paper A in docs): per-epoch GNSS features -> PSO-SVM +
// HMM + joint vote -> recognised region -> region-aware IMM over three planar IMU-driven EKF
// sub-models, and the baselines it is compared with (GNSS alone, UWB alone, each sub-model
// alone, federated Kalman filter, plain IMM). It runs on sensor streams (messages::SensorLog), from a
// recording or the simulator alike, and never reads truth:
//   region_imm/settings.hpp    the one set of settings, the estimators, recognised regions
//   region_imm/recogniser.hpp  features, recognition (no libsvm)
//   region_imm/training.hpp    training the recogniser from labelled logs (libsvm)
//   region_imm/alignment.hpp   how the filters start (dynamic alignment from fixes)
//   region_imm/models.hpp      measurement models, lock-out recovery, integrity monitor
//   region_imm/aided.hpp       the aided-filter wrapper every IMU-driven estimator runs in
//   region_imm/estimators.hpp  sub-model, federated filter, IMM (plain and region-aware)
//   region_imm/baselines.hpp   GNSS alone, UWB alone
//   region_imm/run.hpp         run(): one estimator over a log
// Scoring against truth: eval/region_errors.hpp.
#pragma once

#include "ctxfuse/pipelines/region_imm/alignment.hpp"
#include "ctxfuse/pipelines/region_imm/recogniser.hpp"
#include "ctxfuse/pipelines/region_imm/training.hpp"
#include "ctxfuse/pipelines/region_imm/run.hpp"
#include "ctxfuse/pipelines/region_imm/settings.hpp"

// The region paper's tables 2-6 (recognition accuracy; mean error per region of the single
// sensors, single sub-models, FKF, plain IMM and region-aware IMM; X/Y RMSE) with ours side by
// side, for one log and its truth. One report for `ctxfuse demo` (section "region_imm", on
// the simulated drive) and `ctxfuse run region-imm` (on logs): the same log gives the same
// numbers, key for key.
#pragma once

#include <ostream>
#include <span>
#include <string>

#include "cli/json.hpp"
#include "cli/plot.hpp"
#include "ctxfuse/eval/truth.hpp"
#include "ctxfuse/pipelines/region_imm.hpp"
#include "ctxfuse/sim/config.hpp"

namespace ctxfuse::cli {

namespace ri = pipelines::region_imm;

struct RegionImmRun {
  const messages::SensorLog& log;
  const sim::TruthLog& truth;
  const ri::Recogniser& recogniser;
  std::string recogniser_note;  // how it was trained, for the heading line
  Plotter* plotter = nullptr;
};

/// Prints the tables to `out` and fills `json` (the keys of docs/formats.md, "region_imm");
/// returns the region IMM's track.
ri::Track region_imm_report(const RegionImmRun& in, Json& json, std::ostream& out);

// The pipeline's heavy entry points, compiled once for the whole tool in
// cli/region_imm_report.cpp: each is a large instantiation (every estimator of ri::run, the
// recogniser's PSO-SVM training), and the demo section, `run region-imm` and `region-study`
// would otherwise each compile their own copy.
ri::RunResult run_region_pipeline(const messages::SensorLog& log, ri::Estimator e, const ri::Settings& s, const ri::RunOptions& o = {});
ri::Recogniser train_region_recogniser(const sim::DriveConfig& test);  // ctxfuse::studies::train_recogniser_for
ri::Recogniser train_region_recogniser(std::span<const ri::LabelledFeatures> train, const ri::LabelledFeatures& validate);

}  // namespace ctxfuse::cli

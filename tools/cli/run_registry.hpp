// Pipelines for `ctxfuse run PIPELINE --data DIR`. A pipeline turns the sensor streams of a set
// of logs (the files of `ctxfuse sim`, read by ctxfuse/sim/logs.hpp, truth kept apart) into
// a trajectory; `run` scores it against truth.csv and writes the JSON and CSV outputs. Each
// pipeline declares its own options on a CLI11 sub-command and lists the files it reads (shown
// by `ctxfuse run --help`). Pipelines register themselves from their own tools/cli/*.cpp:
//   static ctxfuse::cli::RegisterRunPipeline reg{{"name", "one-line summary", "files it reads",
//       add_options, run}};
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <ostream>
#include <string_view>
#include <vector>

#include "cli/json.hpp"
#include "cli/options.hpp"
#include "ctxfuse/eval/trajectory.hpp"
#include "ctxfuse/eval/truth.hpp"
#include "ctxfuse/messages/sensors.hpp"

namespace ctxfuse::cli {

class Plotter;

struct RunInput {
  const messages::SensorLog& sensors;
  const sim::TruthLog& truth;  // for scoring only; a pipeline never reads it to estimate
  std::filesystem::path data_dir;
  std::ostream& out;  // the pipeline's own tables, printed before the scores
  Plotter* plotter = nullptr;
};

struct RunOutput {
  std::vector<eval::TimedPosition> trajectory;  // ENU estimates; scored against truth by `run`
  Json json;  // pipeline-specific results, written under "pipeline" in --json
};

/// For a pipeline that reads its own folder format (not the logs of `ctxfuse sim`): the common
/// options as given; the pipeline reads, scores and writes its outputs itself.
struct FolderRunInput {
  std::filesystem::path data_dir;
  std::string out_csv, json, plot;  // empty: not asked for
  std::ostream& out;
};

struct RunPipeline {
  std::string_view name;
  std::string_view summary;
  std::string_view reads;  // the files it reads from DIR (and elsewhere), for --help
  // Declares the pipeline's own options on its sub-command; the state they fill lives in the
  // returned object, which run() receives back.
  std::function<std::shared_ptr<void>(CLI::App& app)> add_options;
  // Returns 0 on success, 1 on a runtime failure (message already written to err).
  std::function<int(const std::shared_ptr<void>& options, const RunInput& in, RunOutput& out, std::ostream& err)> run;
  // Set instead of `run` by a pipeline with its own folder format (e.g. `uwb` on a Hanyang case).
  std::function<int(const std::shared_ptr<void>& options, const FolderRunInput& in, std::ostream& err)> run_folder = {};
};

inline std::vector<RunPipeline>& run_pipelines() {
  static std::vector<RunPipeline> list;
  return list;
}

struct RegisterRunPipeline {
  explicit RegisterRunPipeline(RunPipeline p) { run_pipelines().push_back(std::move(p)); }
};

}  // namespace ctxfuse::cli

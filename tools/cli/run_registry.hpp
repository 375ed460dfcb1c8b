// Pipelines for `ctxfuse run PIPELINE --data DIR`. A pipeline turns a set of logs (the files
// of `ctxfuse sim`, read by ctxfuse/sim/log_io.hpp) into a trajectory; `run` scores it against
// truth.csv and writes the JSON and CSV outputs. Pipelines register themselves from their own
// tools/cli/*.cpp:
//   static ctxfuse::cli::RegisterRunPipeline reg{{"name", "one-line summary",
//       [](const ctxfuse::cli::RunInput& in, ctxfuse::cli::RunOutput& out, std::ostream& err) -> int {...}}};
#pragma once

#include <filesystem>
#include <functional>
#include <ostream>
#include <string_view>
#include <vector>

#include "cli/json.hpp"
#include "ctxfuse/eval/trajectory.hpp"
#include "ctxfuse/sim/log_io.hpp"

namespace ctxfuse::cli {

struct RunInput {
  const sim::DriveLog& log;
  std::filesystem::path data_dir;
};

struct RunOutput {
  std::vector<eval::TimedPosition> trajectory;  // ENU estimates; scored against truth by `run`
  Json json;  // pipeline-specific results, written under "pipeline" in --json
};

struct RunPipeline {
  std::string_view name;
  std::string_view summary;
  // Returns 0 on success, 1 on a runtime failure (message already written to err).
  std::function<int(const RunInput& in, RunOutput& out, std::ostream& err)> run;
};

inline std::vector<RunPipeline>& run_pipelines() {
  static std::vector<RunPipeline> list;
  return list;
}

struct RegisterRunPipeline {
  explicit RegisterRunPipeline(RunPipeline p) { run_pipelines().push_back(std::move(p)); }
};

}  // namespace ctxfuse::cli

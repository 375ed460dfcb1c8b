// Registration points of the ctxfuse CLI. Sub-commands ("demo", "run", "classify", ...)
// and the sections of `ctxfuse demo` live in separate translation units and register
// themselves at static-initialisation time, so adding a pipeline never edits main.cpp.
#pragma once

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "cli/json.hpp"

namespace ctxfuse::sim {
struct Drive;
}

namespace ctxfuse::cli {

class Plotter;

/// Arguments after the sub-command name, e.g. for `ctxfuse run region --data x` the
/// command "run" receives {"region", "--data", "x"}.
using Args = std::span<const std::string_view>;

struct Command {
  std::string_view name;
  std::string_view summary;  // one line for `ctxfuse --help`
  // Returns the process exit code: 0 success, 1 runtime failure, 2 usage error.
  std::function<int(Args args, std::ostream& out, std::ostream& err)> run;
};

/// What every `ctxfuse demo` section receives.
struct DemoContext {
  std::uint64_t seed = 1;
  /// The simulated default drive (ctxfuse/sim/drive.hpp), shared by all sections.
  const sim::Drive* drive = nullptr;
  /// Non-null with `--plot DIR` (cli/plot.hpp): sections may add PNGs through it.
  Plotter* plotter = nullptr;
};

/// One section of `ctxfuse demo`, keyed like the JSON document ("region_imm", "scene_gins",
/// "nlos_uwb", "phone_gins", "latency_us"). It prints the paper's table and ours side by
/// side to `out` and fills `json` (the sub-object under its key).
struct DemoSection {
  std::string_view key;
  std::string_view title;
  std::function<void(const DemoContext& ctx, Json& json, std::ostream& out)> run;
};

std::vector<Command>& commands();
std::vector<DemoSection>& demo_sections();

struct RegisterCommand {
  explicit RegisterCommand(Command c) { commands().push_back(std::move(c)); }
};
struct RegisterDemoSection {
  explicit RegisterDemoSection(DemoSection s) { demo_sections().push_back(std::move(s)); }
};

}  // namespace ctxfuse::cli

// `--scenario NAME` of the commands that simulate a drive (demo, region-study).
#pragma once

#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <string_view>

#include "cli/cli_args.hpp"
#include "ctxfuse/sim/scenarios.hpp"

namespace ctxfuse::cli {

/// The drive configuration the --scenario flag names ("default" without the flag); nothing,
/// with "ctxfuse <command>: --scenario: <reason>" on `err`, for an unknown name.
inline std::optional<sim::DriveConfig> scenario_from_flags(const FlagParser& flags, std::string_view command,
                                                           std::ostream& err) {
  try {
    return sim::scenario_config(flags.get("--scenario").value_or("default"));
  } catch (const std::invalid_argument& e) {
    err << "ctxfuse " << command << ": --scenario: " << e.what() << '\n';
    return std::nullopt;
  }
}

}  // namespace ctxfuse::cli

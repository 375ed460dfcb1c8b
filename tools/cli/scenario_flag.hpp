// The scenario flags of the commands that simulate a drive (demo, region-study): `--scenario
// NAME` and the indoor-fix modifiers applied on top of it.
#pragma once

#include <initializer_list>
#include <optional>
#include <ostream>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>

#include "cli/cli_args.hpp"
#include "ctxfuse/sim/drive.hpp"
#include "ctxfuse/sim/scenarios.hpp"

namespace ctxfuse::cli {

/// The flags scenario_from_flags reads, for a command's FlagParser.
inline std::set<std::string, std::less<>> with_scenario_flags(std::initializer_list<std::string> own) {
  std::set<std::string, std::less<>> flags(own);
  flags.insert({"--scenario", "--indoor-fix-error", "--indoor-fix-reported-ratio"});
  return flags;
}

/// Those flags in a usage line, and their help text.
inline constexpr const char* kScenarioFlagsUsage =
    "[--scenario default|paper] [--indoor-fix-error M] [--indoor-fix-reported-ratio R]";
inline constexpr const char* kScenarioFlagsHelp =
    "  --scenario NAME                 sim::scenario_config: default (the library's drive) or paper (the\n"
    "                                  sensor picture the region paper describes: every UWB anchor inside\n"
    "                                  the garage, its outer walls opaque to UWB; sim/scenarios.hpp)\n"
    "  --indoor-fix-error M            the GNSS receiver keeps reporting fixes indoors, with a Gauss-Markov\n"
    "                                  error of M metres std per axis (GnssConfig::indoor_fix_error_m; 0: none)\n"
    "  --indoor-fix-reported-ratio R   those fixes' reported sigma is R * M (default 1; below 1: over-confident)\n";

/// The drive configuration the flags name ("default" without --scenario); nothing, with
/// "ctxfuse <command>: <flag>: <reason>" on `err`, for an unknown name or a bad modifier.
inline std::optional<sim::DriveConfig> scenario_from_flags(const FlagParser& flags, std::string_view command,
                                                           std::ostream& err) {
  sim::DriveConfig c;
  try {
    c = sim::scenario_config(flags.get("--scenario").value_or("default"));
  } catch (const std::invalid_argument& e) {
    err << "ctxfuse " << command << ": --scenario: " << e.what() << '\n';
    return std::nullopt;
  }
  if (!flags.get_double("--indoor-fix-error", c.gnss.indoor_fix_error_m, err) ||
      !flags.get_double("--indoor-fix-reported-ratio", c.gnss.indoor_fix_reported_ratio, err))
    return std::nullopt;
  try {
    sim::detail::check_config(c);
  } catch (const std::invalid_argument& e) {
    err << "ctxfuse " << command << ": --indoor-fix-error / --indoor-fix-reported-ratio: " << e.what() << '\n';
    return std::nullopt;
  }
  return c;
}

/// The scenario's name as reported in a command's output and JSON: the --scenario name, with
/// the indoor-fix modifiers when given.
inline std::string scenario_label(const FlagParser& flags) {
  std::string label = flags.get("--scenario").value_or("default");
  if (auto e = flags.get("--indoor-fix-error")) label += " + indoor fixes " + *e + " m";
  if (auto r = flags.get("--indoor-fix-reported-ratio")) label += " reported x" + *r;
  return label;
}

}  // namespace ctxfuse::cli

// The scenario options of the commands that simulate a drive (sim, demo, region-study):
// `--scenario NAME` and the indoor-fix modifiers applied on top of it.
#pragma once

#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <string_view>

#include "cli/options.hpp"
#include "ctxfuse/sim/drive.hpp"
#include "ctxfuse/sim/scenarios.hpp"

namespace ctxfuse::cli {

struct ScenarioOptions {
  std::string scenario = "default";
  double indoor_fix_error_m = 0.0;
  double indoor_fix_reported_ratio = 1.0;
  CLI::Option* error_option = nullptr;
  CLI::Option* ratio_option = nullptr;
};

/// Declares --scenario, --indoor-fix-error and --indoor-fix-reported-ratio on `app`.
inline void add_scenario_options(CLI::App& app, ScenarioOptions& o) {
  app.add_option("--scenario", o.scenario,
                 "sim::scenario_config: default (the library's drive) or paper (the sensor picture the region paper "
                 "describes: every UWB anchor inside the garage, its outer walls opaque to UWB; sim/scenarios.hpp)")
      ->check(CLI::IsMember({"default", "paper"}));
  o.error_option = app.add_option("--indoor-fix-error", o.indoor_fix_error_m,
                                  "the GNSS receiver keeps reporting fixes indoors, with a Gauss-Markov error of this many "
                                  "metres std per axis (GnssConfig::indoor_fix_error_m; 0: none)");
  o.ratio_option = app.add_option("--indoor-fix-reported-ratio", o.indoor_fix_reported_ratio,
                                  "those fixes' reported sigma is this times the error (below 1: over-confident)");
}

/// The drive configuration the options name; nothing, with "ctxfuse <command>: <option>:
/// <reason>" on `err`, for a bad modifier.
inline std::optional<sim::DriveConfig> scenario_config(const ScenarioOptions& o, std::string_view command, std::ostream& err) {
  sim::DriveConfig c;
  try {
    c = sim::scenario_config(o.scenario);
  } catch (const std::invalid_argument& e) {
    err << "ctxfuse " << command << ": --scenario: " << e.what() << '\n';
    return std::nullopt;
  }
  c.gnss.indoor_fix_error_m = o.indoor_fix_error_m;
  c.gnss.indoor_fix_reported_ratio = o.indoor_fix_reported_ratio;
  try {
    sim::detail::check_config(c);
  } catch (const std::invalid_argument& e) {
    err << "ctxfuse " << command << ": --indoor-fix-error / --indoor-fix-reported-ratio: " << e.what() << '\n';
    return std::nullopt;
  }
  return c;
}

/// The scenario's name as reported in a command's output and JSON: the --scenario name, with
/// the indoor-fix modifiers when given (as typed).
inline std::string scenario_label(const ScenarioOptions& o) {
  std::string label = o.scenario;
  if (o.error_option && o.error_option->count() > 0) label += " + indoor fixes " + o.error_option->as<std::string>() + " m";
  if (o.ratio_option && o.ratio_option->count() > 0) label += " reported x" + o.ratio_option->as<std::string>();
  return label;
}

}  // namespace ctxfuse::cli

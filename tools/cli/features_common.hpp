// Shared by the `ctxfuse features` sub-commands (features_*.cpp): number formatting, output
// files, and the entry point of each sub-command.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdio>
#include <fstream>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>
#include <ctxfuse/features/gnss_scene.hpp>

#include "cli/options.hpp"
#include "cli/registry.hpp"

namespace ctxfuse::cli::features_cli {

/// A problem with the input files: exit status 1.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

inline std::string fmt(double v) {
  if (!std::isfinite(v)) return "nan";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

inline std::unique_ptr<std::ofstream> open_out(const std::string& path) {
  auto f = std::make_unique<std::ofstream>(path);
  if (!*f) throw std::runtime_error("cannot write '" + path + "'");
  return f;
}

/// A usage problem found after parsing: the message, a pointer to --help, exit status 2.
inline int usage_error(std::ostream& err, const std::string& command, const std::string& what) {
  err << "ctxfuse " << command << ": " << what << "\n(`ctxfuse " << command << " --help` lists the options)\n";
  return 2;
}

/// --window, --cn0-window and --fill of the scene features (windows in seconds).
inline void add_window_options(CLI::App& app, features::GnssSceneConfig& c) {
  app.add_option("--window", c.window_s, "window [s] of the satellite-count and PDOP std (the paper: 4 epochs at 1 Hz)")
      ->check(ctxfuse::cli::kPositiveNumber);
  app.add_option("--cn0-window", c.cn0_window_s, "window [s] of the per-satellite C/N0 std (the paper: 4 epochs at 1 Hz)")
      ->check(ctxfuse::cli::kPositiveNumber);
  app.add_option("--fill", c.fill_value, "value of a feature that cannot be computed (e.g. PDOP with < 4 satellites)");
}

int run_gnss(Args args, std::ostream& out, std::ostream& err);
int run_nmea(Args args, std::ostream& out, std::ostream& err);
int run_uwb_static(Args args, std::ostream& out, std::ostream& err);
int run_dw1000(Args args, std::ostream& out, std::ostream& err);

}  // namespace ctxfuse::cli::features_cli

// `ctxfuse sim [--seed N] [--scenario NAME ...] --out DIR [--duration S]`: writes the simulated
// drive as CSV logs (docs/formats.md), every number in its shortest round-trip form, so that a
// pipeline run on the logs (`ctxfuse run`) sees exactly what it sees on the drive itself.
#include <iostream>
#include <string>

#include "cli/options.hpp"
#include "cli/registry.hpp"
#include "cli/scenario_flag.hpp"
#include "ctxfuse/io/sim_logs.hpp"

namespace ctxfuse::cli {
namespace {

int sim_command(Args args, std::ostream& out, std::ostream& err) {
  CLI::App app = make_app("sim",
                          "Simulates the drive (outdoor -> transition -> indoor garage and back) and writes imu.csv gnss.csv\n"
                          "sats.csv uwb.csv speed.csv mag.csv truth.csv into DIR (docs/formats.md).");
  std::uint64_t seed = 1;
  double duration = sim::DriveConfig{}.route.duration_s;
  std::string dir;
  ScenarioOptions scenario_options;
  app.add_option("--seed", seed, "seed of the drive")->check(kNonNegativeInteger);
  add_scenario_options(app, scenario_options);
  auto* duration_option = app.add_option("--duration", duration, "length of the drive [s] (default: the scenario's)");
  app.add_option("--out", dir, "directory to write the logs into (created if needed)")->required();
  if (const auto rc = parse_options(app, args, out, err)) return *rc;
  std::optional<sim::DriveConfig> cfg = scenario_config(scenario_options, "sim", err);
  if (!cfg) return 2;
  cfg->seed = seed;
  if (duration_option->count() > 0) cfg->route.duration_s = duration;
  sim::Drive drive;
  try {
    drive = sim::simulate_drive(*cfg);
  } catch (const std::invalid_argument& e) {
    err << "ctxfuse sim: " << e.what() << '\n';
    return 2;
  }
  try {
    io::write_drive_logs(drive, dir);
  } catch (const std::exception& e) {
    err << "ctxfuse sim: " << e.what() << '\n';
    return 1;
  }
  out << "wrote " << drive.duration() << " s drive (seed " << cfg->seed << ", scenario " << scenario_label(scenario_options) << ") to " << dir
      << ": " << drive.imu.size() << " imu, " << drive.gnss.size() << " gnss epochs, " << drive.sats.size() << " satellite rows, "
      << drive.uwb.size() << " uwb ranges, " << drive.speed.size() << " speed, " << drive.mag.size() << " mag, " << drive.truth.size()
      << " truth rows\n";
  return 0;
}

const RegisterCommand reg_sim{{"sim", "write a simulated drive as CSV logs", sim_command}};

}  // namespace
}  // namespace ctxfuse::cli

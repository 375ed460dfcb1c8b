// `ctxfuse sim --seed N --out DIR [--duration S]`: writes the simulated drive as CSV logs.
#include <iostream>

#include "cli/cli_args.hpp"
#include "cli/registry.hpp"
#include "ctxfuse/sim/log_io.hpp"

namespace ctxfuse::cli {
namespace {

int sim_command(Args args, std::ostream& out, std::ostream& err) {
  if (wants_help(args)) {
    out << "usage: ctxfuse sim [--seed N] --out DIR [--duration SECONDS]\n"
           "Simulates the default drive (outdoor -> transition -> indoor garage and back) and writes\n"
           "imu.csv gnss.csv sats.csv uwb.csv speed.csv mag.csv truth.csv into DIR (docs/formats.md).\n";
    return 0;
  }
  FlagParser flags("sim", {"--seed", "--out", "--duration"});
  if (!flags.parse(args, err)) return 2;
  if (!flags.positionals().empty()) {
    err << "ctxfuse sim: unexpected argument '" << flags.positionals()[0] << "'\n";
    return 2;
  }
  sim::DriveConfig cfg;
  if (!flags.get_u64("--seed", cfg.seed, err)) return 2;
  if (!flags.get_double("--duration", cfg.route.duration_s, err)) return 2;
  const auto dir = flags.get("--out");
  if (!dir) {
    err << "ctxfuse sim: --out DIR is required\n";
    return 2;
  }
  sim::Drive drive;
  try {
    drive = sim::simulate_drive(cfg);
  } catch (const std::invalid_argument& e) {
    err << "ctxfuse sim: " << e.what() << '\n';
    return 2;
  }
  try {
    sim::write_drive_logs(drive, *dir);
  } catch (const std::exception& e) {
    err << "ctxfuse sim: " << e.what() << '\n';
    return 1;
  }
  out << "wrote " << drive.duration() << " s drive (seed " << cfg.seed << ") to " << *dir << ": " << drive.imu.size() << " imu, "
      << drive.gnss.size() << " gnss epochs, " << drive.sats.size() << " satellite rows, " << drive.uwb.size() << " uwb ranges, "
      << drive.speed.size() << " speed, " << drive.mag.size() << " mag, " << drive.truth.size() << " truth rows\n";
  return 0;
}

const RegisterCommand reg{{"sim", "write a simulated drive as CSV logs", sim_command}};

}  // namespace
}  // namespace ctxfuse::cli

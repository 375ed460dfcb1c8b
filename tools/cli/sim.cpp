// `ctxfuse sim [--seed N] [--scenario NAME ...] --out DIR [--duration S]`: writes the simulated
// drive as CSV logs (docs/formats.md), every number in its shortest round-trip form, so that a
// pipeline run on the logs (`ctxfuse run`) sees exactly what it sees on the drive itself.
// `ctxfuse sim --platform pedestrian|robot --out DIR [--seed N] [--duration S]`: a walk or a
// ground robot in a yard (sim/platform_run.hpp) written as a recording in the real formats
// (RTKLIB .pos, IMU csv + .tag; the truth in DIR/reference; a UWB site in the Hanyang layout in
// DIR/uwb: sim/platform_recording.hpp), which `ctxfuse run gins` and `ctxfuse run uwb` read
// unchanged.
#include <iostream>
#include <string>

#include "cli/options.hpp"
#include "cli/registry.hpp"
#include "cli/scenario_flag.hpp"
#include "ctxfuse/sim/logs.hpp"
#include "ctxfuse/sim/platform_recording.hpp"

namespace ctxfuse::cli {
namespace {

int platform_command(const std::string& platform, std::uint64_t seed, double duration, const std::string& dir, std::ostream& out,
                     std::ostream& err) {
  sim::PlatformRunConfig c;
  c.kind = platform == "robot" ? sim::PlatformKind::robot : sim::PlatformKind::pedestrian;
  c.seed = seed;
  if (duration > 0.0) c.duration_s = duration;
  sim::PlatformRun run;
  try {
    run = sim::simulate_platform_run(c);
  } catch (const std::invalid_argument& e) {
    err << "ctxfuse sim: " << e.what() << '\n';
    return 2;
  }
  try {
    sim::write_platform_recording(run, dir);
  } catch (const std::exception& e) {
    err << "ctxfuse sim: " << e.what() << '\n';
    return 1;
  }
  std::size_t floats = 0;
  for (const auto& f : run.fixes) floats += f.quality == messages::FixQuality::floating;
  out << "wrote a " << c.duration_s << " s " << platform << " run (seed " << seed << ") to " << dir << ": " << run.imu.size()
      << " IMU samples, " << run.fixes.size() << " GNSS epochs (" << floats << " float), at rest for the first " << run.moving_off_s
      << " s; truth in " << (std::filesystem::path(dir) / "reference" / "truth.pos").string() << "; a UWB site (8 anchors, 100 Hz) in "
      << (std::filesystem::path(dir) / "uwb").string() << '\n';
  return 0;
}

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
  std::string platform;
  app.add_option("--platform", platform,
                 "pedestrian or robot: instead of the drive, a walk (1.2 m/s, handheld IMU at ~140 Hz with jittered stamps) or a "
                 "ground robot (0.3 m/s) in a 20 m yard, 4 Hz RTK fixes with float stretches, written as a recording in the real "
                 "formats (gnss.pos, imu.csv + .tag; truth in reference/truth.pos) for `ctxfuse run gins`, and a UWB site in "
                 "the Hanyang layout (uwb/A<id>.csv, uwb/trajectory.csv) for `ctxfuse run uwb`")
      ->check(CLI::IsMember({"pedestrian", "robot"}));
  if (const auto rc = parse_options(app, args, out, err)) return *rc;
  if (!platform.empty()) return platform_command(platform, seed, duration_option->count() > 0 ? duration : 0.0, dir, out, err);
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
    sim::write_drive_logs(drive, dir);
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

// `ctxfuse run PIPELINE --data DIR [--json FILE] [--out TRAJ.csv]`: runs a registered pipeline
// on a directory of logs (as written by `ctxfuse sim`) and scores it against truth.csv.
#include <fstream>
#include <iostream>

#include "cli/cli_args.hpp"
#include "cli/error_report.hpp"
#include "cli/progress.hpp"
#include "cli/registry.hpp"
#include "cli/run_registry.hpp"

namespace ctxfuse::cli {
namespace {

void list_pipelines(std::ostream& os) {
  os << "available pipelines:\n";
  for (const auto& p : run_pipelines()) os << "  " << p.name << std::string(14 - std::min<std::size_t>(13, p.name.size()), ' ') << p.summary << '\n';
}

int run_command(Args args, std::ostream& out, std::ostream& err) {
  if (wants_help(args)) {
    out << "usage: ctxfuse run PIPELINE --data DIR [--json FILE] [--out TRAJ.csv]\n"
           "Runs PIPELINE on the logs in DIR (imu.csv, gnss.csv, sats.csv, uwb.csv, speed.csv, mag.csv,\n"
           "truth.csv; see docs/formats.md) and prints its position errors against truth.csv by region.\n\n";
    list_pipelines(out);
    return 0;
  }
  FlagParser flags("run", {"--data", "--json", "--out"});
  if (!flags.parse(args, err)) return 2;
  if (flags.positionals().size() != 1) {
    err << "ctxfuse run: expected one PIPELINE name\n";
    list_pipelines(err);
    return 2;
  }
  const std::string& name = flags.positionals()[0];
  const RunPipeline* pipeline = nullptr;
  for (const auto& p : run_pipelines())
    if (p.name == name) pipeline = &p;
  if (!pipeline) {
    err << "ctxfuse run: unknown pipeline '" << name << "'\n";
    list_pipelines(err);
    return 2;
  }
  const auto data = flags.get("--data");
  if (!data) {
    err << "ctxfuse run: --data DIR is required\n";
    return 2;
  }
  sim::DriveLog log;
  try {
    log = sim::read_drive_logs(*data);
  } catch (const sim::LogError& e) {
    err << "ctxfuse run: " << e.what() << '\n';
    return 1;
  }
  RunOutput result;
  const int rc = pipeline->run(RunInput{log, *data}, result, err);
  if (rc != 0) return rc;

  Json doc;
  doc["pipeline_name"] = std::string(name);
  doc["data"] = *data;
  doc["estimates"] = static_cast<double>(result.trajectory.size());
  const auto aligned = eval::align_to_truth(result.trajectory, log.truth);
  const auto overall = eval::position_error_stats(aligned.errors);
  const auto by_region = eval::position_error_stats_by_label(aligned.errors, aligned.region, sim::kRegionCount);
  out << "pipeline " << name << ": " << result.trajectory.size() << " estimates, " << aligned.errors.size()
      << " scored against truth.csv (horizontal error, m)\n";
  print_region_table(out, by_region, overall);
  doc["overall"] = stats_json(overall);
  for (std::size_t r = 0; r < by_region.size(); ++r) doc[sim::region_name(static_cast<sim::Region>(r))] = stats_json(by_region[r]);
  doc["pipeline"] = std::move(result.json);

  if (auto path = flags.get("--out")) {
    std::ofstream os(*path);
    os << "t,east,north,up\n";
    char buf[128];
    for (const auto& p : result.trajectory) {
      std::snprintf(buf, sizeof buf, "%.10g,%.10g,%.10g,%.10g\n", p.t, p.position.x(), p.position.y(), p.position.z());
      os << buf;
    }
    if (!os) {
      err << "ctxfuse run: cannot write " << *path << '\n';
      return 1;
    }
  }
  if (auto path = flags.get("--json"); path && !write_json_file(doc, *path, "run", err)) return 1;
  return 0;
}

// Baseline: the receiver's own fixes (the papers' "GNSS alone").
int gnss_only(const RunInput& in, RunOutput& out, std::ostream&) {
  int fixes = 0;
  for (const auto& e : in.log.gnss) {
    if (!e.has_fix) continue;
    out.trajectory.push_back({e.t, e.position});
    ++fixes;
  }
  out.json["fixes"] = fixes;
  out.json["epochs"] = static_cast<double>(in.log.gnss.size());
  return 0;
}

const RegisterCommand reg_run{{"run", "run a pipeline on logs and score it against truth", run_command}};
const RegisterRunPipeline reg_gnss{{"gnss", "GNSS fixes alone (baseline; no fix indoors)", gnss_only}};

}  // namespace
}  // namespace ctxfuse::cli

// `ctxfuse run PIPELINE --data DIR [--json FILE] [--out TRAJ.csv] [pipeline options]`: runs a
// registered pipeline on a directory of logs (as written by `ctxfuse sim`) and scores it
// against truth.csv. The logs' sensor streams go to the pipeline; truth.csv and the label
// columns only to the scoring.
#include <algorithm>
#include <charconv>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>

#include "cli/error_report.hpp"
#include "cli/options.hpp"
#include "cli/plot.hpp"
#include "cli/registry.hpp"
#include "cli/run_registry.hpp"
#include "ctxfuse/sim/logs.hpp"

namespace ctxfuse::cli {
namespace {

struct CommonOptions {
  std::string data, json, out, plot;
};

int run_pipeline(const RunPipeline& p, const std::shared_ptr<void>& own, const CommonOptions& o, std::ostream& out,
                 std::ostream& err) {
  sim::SimLogs logs;
  try {
    logs = sim::read_sim_logs(o.data);
  } catch (const std::exception& e) {
    err << "ctxfuse run " << p.name << ": " << e.what() << '\n';
    return 1;
  }
  std::unique_ptr<Plotter> plotter;
  if (!o.plot.empty()) plotter = std::make_unique<Plotter>(o.plot, err);
  RunOutput result;
  const RunInput in{logs.sensors, logs.truth, o.data, out, plotter && plotter->available() ? plotter.get() : nullptr};
  if (const int rc = p.run(own, in, result, err); rc != 0) return rc;

  Json doc;
  doc["pipeline_name"] = std::string(p.name);
  doc["data"] = o.data;
  doc["estimates"] = static_cast<double>(result.trajectory.size());
  const auto aligned = eval::align_to_truth(result.trajectory, logs.truth.truth);
  const auto overall = eval::position_error_stats(aligned.errors);
  const auto by_region = eval::position_error_stats_by_label(aligned.errors, aligned.region, sim::kRegionCount);
  out << "pipeline " << p.name << ": " << result.trajectory.size() << " estimates, " << aligned.errors.size()
      << " scored against truth.csv (horizontal error, m)\n";
  print_region_table(out, by_region, overall);
  doc["overall"] = stats_json(overall);
  for (std::size_t r = 0; r < by_region.size(); ++r) doc[sim::region_name(static_cast<sim::Region>(r))] = stats_json(by_region[r]);
  doc["pipeline"] = std::move(result.json);

  if (!o.out.empty()) {
    std::ofstream os(o.out);
    os << "t,east,north,up\n";
    char buf[128];
    for (const auto& e : result.trajectory) {
      // Shortest representation that reads back to the same double.
      char* q = buf;
      for (double v : {e.t, e.position.x(), e.position.y(), e.position.z()}) {
        if (q != buf) *q++ = ',';
        q = std::to_chars(q, buf + sizeof buf - 2, v).ptr;
      }
      *q++ = '\n';
      os.write(buf, q - buf);
    }
    if (!os) {
      err << "ctxfuse run: cannot write " << o.out << '\n';
      return 1;
    }
  }
  if (!o.json.empty() && !write_json_file(doc, o.json, "run", err)) return 1;
  return 0;
}

int run_command(Args args, std::ostream& out, std::ostream& err) {
  CLI::App app = make_app("run",
                          "Runs PIPELINE on the logs in DIR (imu.csv, gnss.csv, sats.csv, uwb.csv, speed.csv, mag.csv, truth.csv;\n"
                          "see docs/formats.md) and prints its position errors against truth.csv by region. The pipeline\n"
                          "sees the sensor streams only; truth.csv and the label columns are read for the scoring.");
  app.require_subcommand(1);
  CommonOptions common;
  struct Slot {
    const RunPipeline* pipeline;
    CLI::App* app;
    std::shared_ptr<void> options;
  };
  std::vector<Slot> slots;
  std::string footer = "\nPipelines and the files they read:\n";
  for (const auto& p : run_pipelines()) {
    CLI::App* sub = app.add_subcommand(std::string(p.name), std::string(p.summary));
    sub->add_option("--data", common.data, p.run_folder ? "the recording's folder (see below)" : "directory of logs (ctxfuse sim --out DIR)")
        ->required()
        ->check(CLI::ExistingDirectory);
    sub->add_option("--json", common.json, "write the scores and the pipeline's results as JSON");
    sub->add_option("--out", common.out, p.run_folder ? "write the trajectory as CSV (see the pipeline)" : "write the trajectory as CSV (t,east,north,up)");
    sub->add_option("--plot", common.plot, "write the pipeline's plots (PNG, gnuplot) into this directory");
    slots.push_back({&p, sub, p.add_options(*sub)});
    footer += "  " + std::string(p.name) + ": " + std::string(p.reads) + "\n";
  }
  app.footer(footer);
  if (!args.empty() && !args[0].starts_with("-") &&
      std::none_of(slots.begin(), slots.end(), [&](const Slot& s) { return s.pipeline->name == args[0]; })) {
    err << "ctxfuse run: unknown pipeline '" << args[0] << "'" << footer;
    return 2;
  }
  if (const auto rc = parse_options(app, args, out, err)) return *rc;
  for (const auto& s : slots)
    if (s.app->parsed()) {
      if (s.pipeline->run_folder) return s.pipeline->run_folder(s.options, {common.data, common.out, common.json, common.plot, out}, err);
      return run_pipeline(*s.pipeline, s.options, common, out, err);
    }
  err << "ctxfuse run: no pipeline given\n";
  return 2;
}

// Baseline: the receiver's own fixes (the papers' "GNSS alone").
int gnss_only(const std::shared_ptr<void>&, const RunInput& in, RunOutput& out, std::ostream&) {
  for (const auto& e : in.sensors.gnss) out.trajectory.push_back({e.t, e.position});
  out.json["fixes"] = static_cast<double>(in.sensors.gnss.size());
  out.json["epochs"] = static_cast<double>(in.sensors.sat_epochs.size());
  return 0;
}

const RegisterCommand reg_run{{"run", "run a pipeline on logs and score it against truth", run_command}};
const RegisterRunPipeline reg_gnss{{"gnss", "GNSS fixes alone (baseline; no fix indoors)", "gnss.csv (truth.csv to score)",
                                    [](CLI::App&) { return std::shared_ptr<void>(); }, gnss_only}};

}  // namespace
}  // namespace ctxfuse::cli

// `ctxfuse run region-imm --data DIR (--train DIR,DIR,... --validate DIR | --recogniser FILE)`:
// the region paper's pipeline on logs (cli/region_imm_report.hpp): the recogniser is trained
// on labelled logs (region labels from each log's truth.csv at its receiver epochs) or loaded
// from a file saved by an earlier run, then every estimator runs on DIR's sensor streams and is
// scored against DIR's truth.csv. For the logs that `ctxfuse sim` writes for the demo's seeds
// (test N, training N+101..N+103, validation N+202) it prints the demo's region_imm numbers.
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "cli/region_imm_report.hpp"
#include "cli/run_registry.hpp"
#include "ctxfuse/instances/region_imm.hpp"  // run() compiled once (ctxfuse::instances)
#include "ctxfuse/studies/region_training.hpp"
#include "ctxfuse/sim/logs.hpp"
#include "ctxfuse/pipelines/region_imm/recogniser_io.hpp"

namespace ctxfuse::cli {
namespace {

struct RegionOptions {
  std::vector<std::string> train;
  std::string validate, recogniser, save_recogniser;
};

std::shared_ptr<void> add_options(CLI::App& app) {
  auto o = std::make_shared<RegionOptions>();
  auto* train = app.add_option("--train", o->train, "training logs (directories), comma-separated; labels from their truth.csv")
                    ->delimiter(',')
                    ->check(CLI::ExistingDirectory);
  auto* validate = app.add_option("--validate", o->validate, "validation log (directory): per-region accuracies weight the joint vote")
                       ->check(CLI::ExistingDirectory);
  auto* load = app.add_option("--recogniser", o->recogniser, "load a trained recogniser instead of training one")->check(CLI::ExistingFile);
  app.add_option("--save-recogniser", o->save_recogniser, "save the recogniser (trained or loaded) to this file");
  train->needs(validate);
  validate->needs(train);
  load->excludes(train)->excludes(validate);
  return o;
}

ri::LabelledFeatures labelled(const std::string& dir) {
  const sim::SimLogs logs = sim::read_sim_logs(dir);
  return ctxfuse::studies::labelled_features(logs.sensors, logs.truth);
}

int run(const std::shared_ptr<void>& opts, const RunInput& in, RunOutput& out, std::ostream& err) {
  const auto& o = *static_cast<const RegionOptions*>(opts.get());
  if (o.recogniser.empty() && o.train.empty()) {
    err << "ctxfuse run region-imm: give --train DIR,... with --validate DIR, or --recogniser FILE\n";
    return 2;
  }
  ri::Recogniser rec;
  std::string note;
  try {
    if (!o.recogniser.empty()) {
      rec = ri::load_recogniser(o.recogniser);
      note = "recogniser loaded from " + o.recogniser;
    } else {
      std::vector<ri::LabelledFeatures> train;
      for (const auto& dir : o.train) train.push_back(labelled(dir));
      rec = train_region_recogniser(std::span<const ri::LabelledFeatures>(train), labelled(o.validate));
      note = "trained on " + std::to_string(train.size()) + " logs, validated on " + o.validate;
    }
    if (!o.save_recogniser.empty()) ri::save_recogniser(o.save_recogniser, rec);
  } catch (const std::exception& e) {
    err << "ctxfuse run region-imm: " << e.what() << '\n';
    return 1;
  }
  ri::Track track;
  try {
    track = region_imm_report({in.sensors, in.truth, rec, note, in.plotter}, out.json, in.out);
  } catch (const std::invalid_argument& e) {
    err << "ctxfuse run region-imm: " << e.what() << '\n';
    return 1;
  }
  for (std::size_t i = 0; i < track.t.size(); ++i) out.trajectory.push_back({track.t[i], Eigen::Vector3d(track.estimate[i].x(), track.estimate[i].y(), 0.0)});
  return 0;
}

const RegisterRunPipeline reg_run_region_imm{{"region-imm", "region paper: recognised regions drive an IMM of three planar EKFs (paper A)",
                               "imu.csv speed.csv uwb.csv gnss.csv sats.csv (truth.csv to score; --train/--validate logs: sats.csv, "
                               "truth.csv for the labels)",
                               add_options, run}};

}  // namespace
}  // namespace ctxfuse::cli

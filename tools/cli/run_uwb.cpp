// `ctxfuse run uwb --data CASE_DIR [--out traj.csv] [--json metrics.json] [--estimator E]
// [--policy P] [--train DIR,...]`: the NLOS-robust UWB pipeline of paper C
// (ctxfuse/pipelines/nlos_uwb) on one Hanyang dynamic case (A<id>.csv ranges; trajectory.csv,
// the reference, to score), every variant and baseline scored with the dataset authors'
// protocol (eval/hanyang_protocol.hpp) beside their RMSD_results.txt. The SVM of p1 is trained
// on --train, by default on the other cases of the same dataset (never on CASE_DIR). --out
// writes the trajectory of the variant --estimator and --policy choose: time_ns,x,y,z, one row
// per estimate (z is the tag's fixed height). Parsing and formatting only: the runs and scores
// are eval::evaluate_nlos_uwb_case.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <memory>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "cli/formatted.hpp"
#include "cli/json.hpp"
#include "cli/options.hpp"
#include "cli/run_registry.hpp"
#include "cli/uwb_plots.hpp"
#include "ctxfuse/eval/nlos_uwb.hpp"

namespace ctxfuse::cli {
namespace {

struct UwbOptions {
  std::string estimator = "calibrated";
  std::string policy = "per-range";
  std::vector<std::string> train;
};

std::shared_ptr<void> add_options(CLI::App& app) {
  auto o = std::make_shared<UwbOptions>();
  app.add_option("--estimator", o->estimator,
                 "estimator of the trajectory written by --out: calibrated (the self-calibrating EKF, newest state), "
                 "calibrated-lag (its fixed-lag output, 0.9 s behind), ekf (the plain EKF)")
      ->check(CLI::IsMember({"calibrated", "calibrated-lag", "ekf"}))
      ->capture_default_str();
  app.add_option("--policy", o->policy, "NLOS policy of the trajectory written by --out: paper (epoch rule), per-range, none")
      ->check(CLI::IsMember({"paper", "per-range", "none"}))
      ->capture_default_str();
  app.add_option("--train", o->train, "cases to train the SVM on, comma-separated (default: the dataset's other cases)")
      ->delimiter(',')
      ->check(CLI::ExistingDirectory);
  return o;
}

Json identification_json(const eval::Identification& m) {
  Json j;
  j["precision"] = m.precision;
  j["recall"] = m.recall;
  j["accuracy"] = m.accuracy;
  j["scored"] = static_cast<double>(m.scored);
  j["labelled_nlos"] = static_cast<double>(m.labelled_nlos);
  return j;
}

bool write_trajectory(const std::string& path, const pipelines::nlos_uwb::Track& track, double z, std::ostream& err) {
  std::ofstream os(path);
  os << "time_ns,x,y,z\n";
  char buf[160];
  for (const auto& e : track.estimates) {
    // Seconds in a double carry ~0.2 us at today's epoch: the ns column is rounded to that.
    const auto t_ns = static_cast<long long>(std::llround(e.t * 1e9));
    std::snprintf(buf, sizeof buf, "%lld,%.17g,%.17g,%.17g\n", t_ns, e.position.x(), e.position.y(), z);
    os << buf;
  }
  if (!os.flush()) {
    err << "ctxfuse run uwb: cannot write " << path << '\n';
    return false;
  }
  return true;
}

/// The authors' protocol error of each estimate alone (NaN outside the scored span): the same
/// numbers as the variant's RMSE, which aggregates them.
std::vector<double> protocol_errors(std::span<const eval::TimedPoint2> est, std::span<const io::HanyangReferencePose> ref,
                                    const eval::HanyangSpan& span) {
  std::vector<double> out;
  eval::hanyang_rmse_2d(est, ref, span, &out);
  return out;
}

std::vector<double> scored(std::vector<double> errors) {
  std::erase_if(errors, [](double e) { return std::isnan(e); });
  return errors;
}

// --plot: the chosen variant against the reference; beside its CDF the paper's pipeline, the
// gate alone, LS, and the authors' ESKF (their ESKF.csv) when the case has it.
void plot_case(const std::string& dir, const eval::NlosUwbCaseReport& rep, const std::string& chosen, const std::filesystem::path& case_dir,
               std::ostream& out, std::ostream& err) {
  Plotter plotter(dir, err);
  if (plotter.available()) {
    const auto span = eval::trajectory_a_span();
    const auto ref = io::read_hanyang_reference(case_dir);
    const auto& track = rep.variant(chosen).track;
    UwbPlots p;
    p.prefix = "uwb";
    p.estimator = chosen;
    for (const auto& r : ref)
      if (std::abs(r.position.z()) < span.max_abs_z) p.reference.push_back(r.position.head<2>());
    std::vector<int> ids;
    for (const auto& rec : track.ranges)
      if (std::find(ids.begin(), ids.end(), rec.range.anchor_id) == ids.end()) {
        ids.push_back(rec.range.anchor_id);
        p.anchors.push_back(rec.range.anchor_position.head<2>());
      }
    const auto errors = protocol_errors(eval::timed_points(track), ref, span);
    for (std::size_t i = 0; i < track.estimates.size(); ++i) {
      const auto& e = track.estimates[i];
      p.estimates.push_back({e.t, e.position, e.epoch_attached, errors[i]});
    }
    p.t0 = track.estimates.empty() ? 0.0 : track.estimates.front().t;
    p.time_label = "time since the first estimate [s]";
    for (const char* name : {"ekf_gate_paper_rule", "ekf_gate", "least_squares"})
      if (name != chosen) p.other_errors.emplace_back(name, scored(protocol_errors(eval::timed_points(rep.variant(name).track), ref, span)));
    if (std::filesystem::exists(case_dir / "ESKF.csv"))
      p.other_errors.emplace_back("authors' ESKF", scored(protocol_errors(eval::read_hanyang_estimates(case_dir / "ESKF.csv"), ref, span)));
    plot_uwb(plotter, p);
  }
  plotter.print_written(out);
}

int run_uwb(const std::shared_ptr<void>& opts, const FolderRunInput& in, std::ostream& err) {
  const auto& o = *static_cast<const UwbOptions*>(opts.get());
  const pipelines::nlos_uwb::Settings settings;
  std::vector<std::filesystem::path> train(o.train.begin(), o.train.end());
  eval::NlosUwbCaseReport rep;
  try {
    if (o.train.empty()) train = eval::other_hanyang_cases(in.data_dir);
    rep = eval::evaluate_nlos_uwb_case(in.data_dir, train, settings, eval::trajectory_a_span());
  } catch (const std::exception& e) {
    err << "ctxfuse run uwb: " << e.what() << '\n';
    return 1;
  }
  const std::string rule = o.policy == "paper" ? "_paper_rule" : o.policy == "none" ? "" : "_per_range";
  const std::string chosen = (o.estimator == "ekf" ? "ekf_gate" : "calibrated_ekf_gate") + rule + (o.estimator == "calibrated-lag" ? "_lag" : "");
  std::ostream& out = in.out;
  out << "uwb on " << in.data_dir.string() << ": SVM " << (rep.svm ? "trained on " + std::to_string(train.size()) + " other cases" : "none (R = p2)")
      << "\n2-D RMSE, authors' protocol (m):\n";
  Json doc, rmse, epochs;
  for (const auto& v : rep.variants) {
    out << formatted("  %-36s %7.3f  (%zu estimates scored, %zu epochs left out)\n", v.name.c_str(), v.rmse.rmse_2d, v.rmse.scored,
                     v.track.epochs_left_out);
    rmse[v.name] = v.rmse.rmse_2d;
    epochs[v.name] = static_cast<double>(v.track.epochs_left_out);
  }
  Json authors;
  for (const char* who : {"LS", "ESKF"})
    if (const auto it = rep.authors.find(std::string(who) + " RMSE_2d"); it != rep.authors.end()) {
      out << formatted("  authors %-28s %7.3f\n", who, it->second);
      authors[who] = it->second;
    }
  out << "NLOS identification against residual labels (paper rule run): precision / recall / accuracy\n";
  const auto& id = rep.identification;
  for (const auto& [name, m] : {std::pair{"svm", id.svm}, std::pair{"consistency", id.consistency}, std::pair{"ds", id.ds}})
    out << formatted("  %-12s %.3f / %.3f / %.3f  (%zu ranges, %zu NLOS)\n", name, m.precision, m.recall, m.accuracy, m.scored,
                     m.labelled_nlos);

  const auto& track = rep.variant(chosen).track;
  doc["pipeline_name"] = "uwb";
  doc["data"] = in.data_dir.string();
  doc["trajectory_variant"] = chosen;
  doc["estimates"] = static_cast<double>(track.estimates.size());
  doc["svm"] = rep.svm;
  if (rep.svm) doc["svm_gamma"] = rep.svm_gamma;
  Json cases = Json::array();
  for (const auto& c : rep.training_cases) cases.push_back(c.string());
  doc["training_cases"] = std::move(cases);
  doc["rmse_2d_m"] = std::move(rmse);
  doc["epochs_left_out"] = std::move(epochs);
  doc["authors_rmse_2d_m"] = std::move(authors);
  doc["identification"]["svm"] = identification_json(id.svm);
  doc["identification"]["consistency"] = identification_json(id.consistency);
  doc["identification"]["ds"] = identification_json(id.ds);
  if (!in.out_csv.empty() && !write_trajectory(in.out_csv, track, settings.tag_height_m, err)) return 1;
  if (!in.json.empty() && !write_json_file(doc, in.json, "run uwb", err)) return 1;
  if (!in.plot.empty()) {
    try {
      plot_case(in.plot, rep, chosen, in.data_dir, out, err);
    } catch (const std::exception& e) {
      err << "ctxfuse run uwb: plots: " << e.what() << '\n';
      return 1;
    }
  }
  return 0;
}

const RegisterRunPipeline reg_run_uwb{{"uwb", "NLOS-robust UWB (paper C) on a Hanyang dynamic case, with its baselines",
                               "A<id>.csv per anchor (trajectory.csv and RMSD_results.txt to score; the other cases of the "
                               "dataset, or --train, for the SVM)",
                               add_options, {}, run_uwb}};

}  // namespace
}  // namespace ctxfuse::cli

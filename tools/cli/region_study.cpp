// `ctxfuse region-study`: why the region IMM does or does not beat the plain IMM and the FKF on
// a simulated drive. Per seed it prints the simulator's sensor picture per zone of the drive,
// how many GNSS and UWB updates each estimator's chi-square gate rejected per zone, and the
// errors; then a summary of the paper's ordering (region IMM < IMM < FKF) over the seeds.
// docs/results.md quotes its numbers, so every printed number is also in the --json document.
// The zones and what is counted in them: studies/region_zones.hpp (printed by cli/region_study_zones.hpp).
//
// Gate counts come from the pipeline's update observer (pipelines/region_imm/aided.hpp,
// UpdateEvent), so the pipeline runs unchanged: the tracks are those of ri::run.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "cli/json.hpp"
#include "cli/options.hpp"
#include "cli/region_imm_report.hpp"
#include "cli/registry.hpp"
#include "cli/region_study_zones.hpp"
#include "cli/scenario_flag.hpp"
#include "cli/seed_list.hpp"
#include "ctxfuse/instances/region_imm.hpp"  // run() compiled once (ctxfuse::instances)
#include "ctxfuse/eval/region_errors.hpp"
#include "ctxfuse/studies/region_training.hpp"
#include "ctxfuse/pipelines/region_imm.hpp"
#include "ctxfuse/sim/drive.hpp"
#include "ctxfuse/sim/streams.hpp"

namespace ctxfuse::cli {
namespace {

namespace ri = pipelines::region_imm;
using namespace region_study;

// ------------------------------------------------------------------ one seed
struct SeedResult {
  std::uint64_t seed = 0;
  eval::TrackErrors fkf, imm, region_imm;
  bool overall_holds = false, transition_holds = false;
};

constexpr std::array<const char*, 4> kRegionColumn{"outdoor", "transition", "indoor", "overall"};

SeedResult study_seed(const sim::DriveConfig& cfg, const ri::Settings& s, std::ostream& out, Json& json) {
  const sim::Drive test = sim::simulate_drive(cfg);
  const Zoning zones(test);
  const messages::SensorLog log = sim::sensor_log(test);
  const auto features = ri::gnss_features(log.sat_epochs);
  const auto labels = eval::region_labels(test.truth, features.t);
  const ri::Recognition r = ri::recognise(train_region_recogniser(cfg), features);
  const auto regions = ri::region_track(features, r.joint);
  const auto true_regions = ri::region_track(features, labels);
  const NlosTruth nlos = nlos_truth(test);

  out << formatted("\n=== seed %llu  (approach mouth at x = %.1f m; drive %.0f s)\n", static_cast<unsigned long long>(cfg.seed), zones.mouth_x,
             test.duration());
  json["seed"] = static_cast<double>(cfg.seed);
  json["approach_mouth_x_m"] = zones.mouth_x;
  json["duration_s"] = test.duration();
  report_picture(sensor_picture(test, zones), out, json["zones"]);

  GateTable g_fkf{}, g_imm{}, g_rimm{};
  GateCounter c_fkf{zones, nlos, g_fkf}, c_imm{zones, nlos, g_imm}, c_rimm{zones, nlos, g_rimm};
  ri::RunOptions with_regions;
  with_regions.regions = &regions;
  const ri::Track t_fkf = ri::run(log, ri::Estimator::fkf, s, {}, &c_fkf).track;
  const ri::Track t_imm = ri::run(log, ri::Estimator::imm, s, {}, &c_imm).track;
  const ri::Track t_rimm = ri::run(log, ri::Estimator::region_imm, s, with_regions, &c_rimm).track;

  out << "  gate rejections, gated/offered per zone (imm: no mode that took the update accepted it):\n";
  report_gates("FKF", g_fkf, 1, out, json["gates"]["fkf"]);
  report_gates("IMM", g_imm, kMaxTakers, out, json["gates"]["imm"]);
  report_gates("regionIMM", g_rimm, kMaxTakers, out, json["gates"]["region_imm"]);
  out << formatted("  UWB integrity re-anchorings (policies/integrity.hpp): FKF %d, IMM %d, region IMM %d\n", t_fkf.integrity_faults,
             t_imm.integrity_faults, t_rimm.integrity_faults);
  json["integrity_faults"]["fkf"] = t_fkf.integrity_faults;
  json["integrity_faults"]["imm"] = t_imm.integrity_faults;
  json["integrity_faults"]["region_imm"] = t_rimm.integrity_faults;

  SeedResult res;
  res.seed = cfg.seed;
  auto score = [&](const ri::Track& tr) { return eval::region_errors(tr, test.truth); };
  auto score_run = [&](ri::Estimator e, const ri::RunOptions& o = {}) { return score(run_region_pipeline(log, e, s, o).track); };
  ri::RunOptions with_true_regions;
  with_true_regions.regions = &true_regions;
  res.fkf = score(t_fkf);
  res.imm = score(t_imm);
  res.region_imm = score(t_rimm);
  struct Row {
    const char* label;
    const char* key;
    eval::TrackErrors e;
  };
  const std::array<Row, 7> rows{{
      {"GNSS", "gnss", score_run(ri::Estimator::gnss)},
      {"UWB", "uwb", score_run(ri::Estimator::uwb)},
      {"EKF-I-OTR", "iotr", score_run(ri::Estimator::iotr)},
      {"FKF", "fkf", res.fkf},
      {"IMM", "imm", res.imm},
      {"region IMM", "region_imm", res.region_imm},
      {"rIMM truelab", "region_imm_true_labels", score_run(ri::Estimator::region_imm, with_true_regions)},
  }};
  out << "  mean horizontal error (m) at the GNSS epochs, per true region: outdoor transition indoor overall\n";
  for (const auto& row : rows) {
    out << formatted("    %-14s %7.3f %7.3f %7.3f %7.3f\n", row.label, row.e.mean[0], row.e.mean[1], row.e.mean[2], row.e.mean[3]);
    for (std::size_t k = 0; k < 4; ++k) json["mean_error_m"][row.key][kRegionColumn[k]] = row.e.mean[k];
  }
  const double a_svm = ri::accuracy(labels, r.svm), a_hmm = ri::accuracy(labels, r.hmm), a_joint = ri::accuracy(labels, r.joint);
  out << formatted("  region recognition accuracy SVM/HMM/joint %.2f/%.2f/%.2f %%\n", 100.0 * a_svm, 100.0 * a_hmm, 100.0 * a_joint);
  json["recognition_accuracy"]["svm"] = a_svm;
  json["recognition_accuracy"]["hmm"] = a_hmm;
  json["recognition_accuracy"]["joint"] = a_joint;

  res.overall_holds = res.region_imm.mean[3] < res.imm.mean[3] && res.imm.mean[3] < res.fkf.mean[3];
  res.transition_holds = res.region_imm.mean[1] < res.imm.mean[1] && res.imm.mean[1] < res.fkf.mean[1];
  json["ordering"]["overall_holds"] = res.overall_holds;
  json["ordering"]["transition_holds"] = res.transition_holds;
  return res;
}

void report_summary(const std::vector<SeedResult>& results, std::string_view header, std::ostream& out, Json& json) {
  out << "\nSummary (" << header << "): mean horizontal error (m); ordering = region IMM < IMM < FKF\n";
  out << "  seed |  overall: FKF     IMM    rIMM  ordering | transition: FKF     IMM    rIMM  ordering\n";
  int overall = 0, transition = 0;
  std::array<double, 6> sum{};
  Json rows = Json::array();
  for (const auto& r : results) {
    out << formatted("  %4llu |        %6.3f  %6.3f  %6.3f  %-8s |           %6.3f  %6.3f  %6.3f  %s\n", static_cast<unsigned long long>(r.seed),
               r.fkf.mean[3], r.imm.mean[3], r.region_imm.mean[3], r.overall_holds ? "holds" : "no", r.fkf.mean[1], r.imm.mean[1],
               r.region_imm.mean[1], r.transition_holds ? "holds" : "no");
    overall += r.overall_holds ? 1 : 0;
    transition += r.transition_holds ? 1 : 0;
    const std::array<double, 6> v{r.fkf.mean[3], r.imm.mean[3], r.region_imm.mean[3], r.fkf.mean[1], r.imm.mean[1], r.region_imm.mean[1]};
    for (std::size_t k = 0; k < v.size(); ++k) sum[k] += v[k];
    Json row;
    row["seed"] = static_cast<double>(r.seed);
    row["overall"]["fkf"] = v[0];
    row["overall"]["imm"] = v[1];
    row["overall"]["region_imm"] = v[2];
    row["overall"]["holds"] = r.overall_holds;
    row["transition"]["fkf"] = v[3];
    row["transition"]["imm"] = v[4];
    row["transition"]["region_imm"] = v[5];
    row["transition"]["holds"] = r.transition_holds;
    rows.push_back(std::move(row));
  }
  const double n = static_cast<double>(results.size());
  out << formatted("  mean |        %6.3f  %6.3f  %6.3f  %2d/%-5zu |           %6.3f  %6.3f  %6.3f  %d/%zu\n", sum[0] / n, sum[1] / n, sum[2] / n,
             overall, results.size(), sum[3] / n, sum[4] / n, sum[5] / n, transition, results.size());
  out << formatted("ordering holds overall on %d/%zu seeds, in the transition region on %d/%zu\n", overall, results.size(), transition,
             results.size());
  json["seeds"] = std::move(rows);
  json["mean_over_seeds"]["overall"]["fkf"] = sum[0] / n;
  json["mean_over_seeds"]["overall"]["imm"] = sum[1] / n;
  json["mean_over_seeds"]["overall"]["region_imm"] = sum[2] / n;
  json["mean_over_seeds"]["transition"]["fkf"] = sum[3] / n;
  json["mean_over_seeds"]["transition"]["imm"] = sum[4] / n;
  json["mean_over_seeds"]["transition"]["region_imm"] = sum[5] / n;
  json["overall_holds_count"] = overall;
  json["transition_holds_count"] = transition;
  json["seed_count"] = static_cast<double>(results.size());
}

// ------------------------------------------------------------------ command
int region_study(Args args, std::ostream& out, std::ostream& err) {
  CLI::App app = make_app(
      "region-study",
      "Per simulated drive (seed): the sensor picture per zone of the drive (out-far, out-near = within\n"
      "30 m of the approach mouth, tr-mouth / tr-door = street / door half of the approach, in-door10 =\n"
      "indoor within 10 m of the door, in-deep), the GNSS/UWB updates each estimator's chi-square gate\n"
      "rejected per zone (FKF; plain IMM and region IMM per mode and as a whole), the mean errors, and\n"
      "a summary of region IMM < IMM < FKF over the seeds. The recogniser is trained as in\n"
      "`ctxfuse demo` (seeds N+101..N+103, validation N+202).");
  ScenarioOptions scenario_options;
  std::string seeds_text = "1-5", json_file;
  bool ungated = false, no_integrity = false;
  add_scenario_options(app, scenario_options);
  app.add_option("--seeds", seeds_text, "seeds, e.g. 1-5, 1,3,7 or 1-3,9");
  app.add_flag("--ungated", ungated, "no chi-square gate (gate probability 1; the lock-out recovery never fires)");
  app.add_flag("--no-integrity", no_integrity,
               "no UWB integrity check (Settings::uwb_integrity off: no re-anchoring to snapshot multilaterations)");
  app.add_option("--json", json_file, "every printed number also as JSON");
  if (const auto rc = parse_options(app, args, out, err)) return *rc;
  const std::string scenario = scenario_label(scenario_options);
  const std::optional<sim::DriveConfig> base = scenario_config(scenario_options, "region-study", err);
  if (!base) return 2;
  std::vector<std::uint64_t> seeds;
  if (!parse_seeds(seeds_text, seeds, err)) return 2;
  const std::optional<std::string> json_path = json_file.empty() ? std::nullopt : std::optional<std::string>(json_file);
  // Tried before the study runs, so that a bad path fails at once.
  if (json_path && !write_json_file(Json{}, *json_path, "region-study", err)) return 1;

  ri::Settings settings;
  if (ungated) settings.gate_probability = 1.0;
  settings.uwb_integrity = !no_integrity;
  const std::string header = "scenario " + scenario + ", " + (ungated ? std::string("ungated") : formatted("gate %g", settings.gate_probability)) +
                             (no_integrity ? ", no integrity check" : "");
  out << "region study: " << header << "\n";
  Json doc;
  doc["scenario"] = scenario;
  doc["ungated"] = ungated;
  doc["uwb_integrity"] = !no_integrity;
  doc["gate_probability"] = settings.gate_probability;
  Json per_seed = Json::array();
  std::vector<SeedResult> results;
  for (const std::uint64_t seed : seeds) {
    sim::DriveConfig cfg = *base;
    cfg.seed = seed;
    Json j;
    results.push_back(study_seed(cfg, settings, out, j));
    per_seed.push_back(std::move(j));
    out.flush();
  }
  doc["per_seed"] = std::move(per_seed);
  report_summary(results, header, out, doc["summary"]);
  if (json_path && !write_json_file(doc, *json_path, "region-study", err)) return 1;
  return 0;
}

const RegisterCommand reg_region_study{{"region-study", "sensor picture, gate rejections and errors per zone (region IMM vs IMM vs FKF)", region_study}};

}  // namespace
}  // namespace ctxfuse::cli

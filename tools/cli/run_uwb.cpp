// `ctxfuse run uwb --data DIR [--out traj.csv] [--json run.json] [--estimator E] [--policy P]
// [--nlos-model FILE | --train DIR,...] [--save-nlos-model FILE] [--range-average auto|N]
// [--tag-height M] [--reference FILE] [--span a|b|auto|none|START/END]`: the NLOS-robust UWB
// pipeline of paper C (ctxfuse/pipelines/nlos_uwb) on a folder of per-anchor A<id>.csv files.
// Running needs nothing else: the report period, epoch window and report averaging come from
// the recording (pipelines/nlos_uwb/recording.hpp), the NLOS classifier is an SVM from
// --nlos-model, one trained on --train or on the dataset's other cases (those with a
// reference), or the consistency check alone. --out writes the trajectory of the variant
// --estimator and --policy choose (time_ns,x,y,z; z is the tag's height). Scoring is a separate
// step, done when there is a reference (--reference, else the folder's trajectory.csv): every
// variant and baseline with the authors' protocol on --span (studies/hanyang_protocol.hpp), or the
// whole run; a reference the span does not fit is a warning, never a failed run. Parsing and
// formatting only: the runs and scores are studies/nlos_uwb.hpp's.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "cli/formatted.hpp"
#include "cli/json.hpp"
#include "cli/options.hpp"
#include "cli/run_registry.hpp"
#include "cli/uwb_plots.hpp"
#include "ctxfuse/classify/svm_io.hpp"
#include "ctxfuse/instances/nlos_uwb.hpp"
#include "ctxfuse/pipelines/nlos_uwb/recording.hpp"

namespace ctxfuse::cli {
namespace {

namespace nu = pipelines::nlos_uwb;

struct UwbOptions {
  std::string estimator = "calibrated";
  std::string policy = "per-range";
  std::vector<std::string> train;
  std::string nlos_model, save_nlos_model, reference, span = "auto", range_average = "auto";
  std::string tag_height = "auto";
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
  app.add_option("--train", o->train,
                 "labelled cases (A<id>.csv + trajectory.csv) to train the NLOS SVM on, comma-separated (default: the "
                 "dataset's other cases that have a reference)")
      ->delimiter(',')
      ->check(CLI::ExistingDirectory);
  app.add_option("--nlos-model", o->nlos_model, "the NLOS SVM from a file (--save-nlos-model of an earlier run) instead of training one")
      ->check(CLI::ExistingFile);
  app.add_option("--save-nlos-model", o->save_nlos_model, "write the SVM this run trained (or loaded) to FILE");
  app.add_option("--range-average", o->range_average,
                 "reports are the mean of N raw ranges: auto (detected on the recording's static start; 1 when it does not "
                 "show) or N in 1..100")
      ->check(CLI::Validator(
          [](std::string& s) {
            int n = 0;
            const bool number = !s.empty() && s.size() <= 3 && s.find_first_not_of("0123456789") == std::string::npos &&
                                (n = std::stoi(s)) >= 1 && n <= 100;
            return s == "auto" || number ? std::string() : "'" + s + "' is neither auto nor an integer in 1..100";
          },
          "auto|N", "range average"))
      ->capture_default_str();
  app.add_option("--tag-height", o->tag_height,
                 "the tag antenna's height in the anchors' frame [m], or auto: fitted to the static start when the anchors' "
                 "heights observe it (vertical sigma <= 0.1 m), else 1 m (the Hanyang authors' protocol compares z with "
                 "reference z + 1)")
      ->check(CLI::Validator(
          [](std::string& s) {
            if (s == "auto") return std::string();
            try {
              std::size_t used = 0;
              const double v = std::stod(s, &used);
              if (used == s.size() && std::isfinite(v) && std::abs(v) <= 1e4) return std::string();
            } catch (const std::exception&) {
            }
            return "'" + s + "' is neither auto nor a height in [-1e4, 1e4] m";
          },
          "auto|M", "tag height"))
      ->capture_default_str();
  app.add_option("--reference", o->reference, "reference to score against (Hanyang trajectory.csv; default: DIR/trajectory.csv if present)")
      ->check(CLI::ExistingFile);
  app.add_option("--span", o->span,
                 "scoring protocol: a or b (the authors' span of trajectory A or B), auto (the one whose gates the reference "
                 "passes, else the whole run), none (whole run), or a span START/END of gates like x>49.3,y>-5/x<=12,y>3.4")
      ->check(CLI::Validator(
          [](std::string& s) {
            if (s == "a" || s == "b" || s == "auto" || s == "none") return std::string();
            ctxfuse::studies::HanyangSpan span;
            return ctxfuse::studies::parse_hanyang_span(s, span);
          },
          "SPAN", "span"))
      ->capture_default_str();
  return o;
}

Json identification_json(const ctxfuse::studies::Identification& m) {
  Json j;
  j["precision"] = m.precision;
  j["recall"] = m.recall;
  j["accuracy"] = m.accuracy;
  j["scored"] = static_cast<double>(m.scored);
  j["labelled_nlos"] = static_cast<double>(m.labelled_nlos);
  return j;
}

bool write_trajectory(const std::string& path, const nu::Track& track, double z, std::ostream& err) {
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

/// Each estimate's error under the protocol (NaN where not scored).
std::vector<double> uwb_errors(std::span<const ctxfuse::studies::TimedPoint2> est, std::span<const io::HanyangReferencePose> ref,
                               const ctxfuse::studies::ScoringProtocol& p) {
  std::vector<double> out;
  ctxfuse::studies::score_2d(est, ref, p, &out);
  return out;
}

std::vector<double> scored(std::vector<double> errors) {
  std::erase_if(errors, [](double e) { return std::isnan(e); });
  return errors;
}

struct UwbScoring {
  std::vector<io::HanyangReferencePose> reference;
  ctxfuse::studies::ScoringProtocol protocol;
};

// --plot: the chosen variant, with the reference when there is one; beside its CDF the paper's
// pipeline, the gate alone, LS, and the authors' ESKF (their ESKF.csv) when the case has it.
void plot_case(const std::string& dir, const std::vector<ctxfuse::studies::NlosUwbVariant>& variants, const std::string& chosen,
               const std::filesystem::path& case_dir, const UwbScoring* scoring, std::ostream& out, std::ostream& err) {
  Plotter plotter(dir, err);
  if (plotter.available()) {
    auto variant = [&](std::string_view name) -> const ctxfuse::studies::NlosUwbVariant* {
      for (const auto& v : variants)
        if (v.name == name) return &v;
      return nullptr;
    };
    const auto& track = variant(chosen)->track;
    UwbPlots p;
    p.prefix = "uwb";
    p.estimator = chosen;
    if (scoring) {
      const double max_z = scoring->protocol.span ? scoring->protocol.span->max_abs_z : std::numeric_limits<double>::infinity();
      for (const auto& r : scoring->reference)
        if (std::abs(r.position.z()) < max_z) p.reference.push_back(r.position.head<2>());
    }
    std::vector<int> ids;
    for (const auto& rec : track.ranges)
      if (std::find(ids.begin(), ids.end(), rec.range.anchor_id) == ids.end()) {
        ids.push_back(rec.range.anchor_id);
        p.anchors.push_back(rec.range.anchor_position.head<2>());
      }
    std::vector<double> errors(track.estimates.size(), std::nan(""));
    if (scoring) errors = uwb_errors(ctxfuse::studies::timed_points(track), scoring->reference, scoring->protocol);
    for (std::size_t i = 0; i < track.estimates.size(); ++i) {
      const auto& e = track.estimates[i];
      p.estimates.push_back({e.t, e.position, e.epoch_attached, errors[i]});
    }
    p.t0 = track.estimates.empty() ? 0.0 : track.estimates.front().t;
    p.time_label = "time since the first estimate [s]";
    if (scoring) {
      for (const char* name : {"ekf_gate_paper_rule", "ekf_gate", "least_squares"})
        if (const auto* v = variant(name); v && name != chosen)
          p.other_errors.emplace_back(name, scored(uwb_errors(ctxfuse::studies::timed_points(v->track), scoring->reference, scoring->protocol)));
      if (std::filesystem::exists(case_dir / "ESKF.csv"))
        p.other_errors.emplace_back("authors' ESKF", scored(uwb_errors(ctxfuse::studies::read_hanyang_estimates(case_dir / "ESKF.csv"),
                                                                       scoring->reference, scoring->protocol)));
    }
    plot_uwb(plotter, p);
  }
  plotter.print_written(out);
}

Json recording_json(const io::HanyangUwbCase& rc, const nu::RecordingFacts& f) {
  Json j, anchors = Json::array();
  for (const auto& a : f.anchors) {
    Json x;
    x["id"] = a.id;
    x["position_m"] = Json(Json::Array{a.position.x(), a.position.y(), a.position.z()});
    x["ranges"] = static_cast<double>(a.ranges);
    x["median_interval_s"] = a.median_interval_s;
    x["rate_hz"] = 1.0 / a.median_interval_s;
    anchors.push_back(std::move(x));
  }
  j["anchors"] = std::move(anchors);
  j["ranges"] = static_cast<double>(rc.ranges.size());
  j["ranges_with_unknown_power"] = static_cast<double>(rc.non_finite_rssi);
  j["duration_s"] = f.t_end - f.t_begin;
  j["static_start_s"] = f.static_start_s;
  Json acf = Json::array();
  for (double a : f.autocorrelation) acf.push_back(a);
  j["range_difference_autocorrelation_lags_1_10"] = std::move(acf);
  j["detected_range_average_samples"] = f.averaging_detected ? Json(f.range_average_samples) : Json(std::nan(""));
  j["range_average_note"] = f.averaging_note;
  return j;
}

Json track_json(const nu::Track& t) {
  Json j;
  j["epochs"] = static_cast<double>(t.epochs);
  j["epochs_attached"] = static_cast<double>(t.epochs_attached);
  j["epochs_left_out"] = static_cast<double>(t.epochs_left_out);
  j["starts"] = static_cast<double>(t.starts);
  j["restarts"] = static_cast<double>(t.restarts);
  j["ranges"] = static_cast<double>(t.ranges.size());
  j["ranges_attached"] = static_cast<double>(t.ranges_attached);
  j["ranges_accepted"] = static_cast<double>(t.ranges_accepted);
  j["ranges_gated"] = static_cast<double>(t.ranges_gated);
  j["ranges_invalid"] = static_cast<double>(t.ranges_invalid);
  std::size_t nlos = 0;
  for (const auto& r : t.ranges) nlos += r.verdict.nlos;
  j["ranges_classified_nlos"] = static_cast<double>(nlos);
  return j;
}

int run_uwb(const std::shared_ptr<void>& opts, const FolderRunInput& in, std::ostream& err) {
  const auto& o = *static_cast<const UwbOptions*>(opts.get());
  std::ostream& out = in.out;
  if (!o.nlos_model.empty() && !o.train.empty()) {
    err << "ctxfuse run uwb: --nlos-model and --train both choose the SVM: give one\n";
    return 2;
  }
  const std::string rule = o.policy == "paper" ? "_paper_rule" : o.policy == "none" ? "" : "_per_range";
  const std::string chosen = (o.estimator == "ekf" ? "ekf_gate" : "calibrated_ekf_gate") + rule + (o.estimator == "calibrated-lag" ? "_lag" : "");

  // --- The run: the recording alone ------------------------------------------------------------
  io::HanyangUwbCase rc;
  nu::RecordingFacts facts;
  nu::Settings settings;
  std::string tag_height_source;
  std::optional<nu::NlosSvm> svm;
  std::string classifier_kind = "consistency-only", classifier_note;
  std::vector<std::filesystem::path> train(o.train.begin(), o.train.end());
  std::vector<ctxfuse::studies::NlosUwbVariant> variants;
  const std::filesystem::path ref_path =
      !o.reference.empty() ? std::filesystem::path(o.reference)
                           : (std::filesystem::exists(in.data_dir / "trajectory.csv") ? in.data_dir / "trajectory.csv" : std::filesystem::path());
  try {
    rc = io::read_hanyang_uwb(in.data_dir);
    const auto ranges = rc.uwb_ranges();
    facts = nu::describe_recording(ranges);
    std::string problem;
    settings = nu::settings_for_recording(facts, nu::Settings{}, o.range_average == "auto" ? 0 : std::stoi(o.range_average), problem,
                                          o.tag_height == "auto" ? std::nan("") : std::stod(o.tag_height), &tag_height_source);
    if (!problem.empty()) {
      err << "ctxfuse run uwb: " << in.data_dir.string() << ": " << problem << '\n';
      return 1;
    }
    for (const auto& c : train)
      if (std::filesystem::weakly_canonical(c) == std::filesystem::weakly_canonical(in.data_dir))
        throw std::invalid_argument("the run's own folder " + in.data_dir.string() + " is among the SVM's training cases");
    if (!o.nlos_model.empty()) {
      svm = classify::load_svm_model<2, 2>(o.nlos_model);
      classifier_kind = "svm-file";
      classifier_note = "loaded from " + o.nlos_model;
    } else {
      if (train.empty()) train = ctxfuse::studies::other_hanyang_cases(in.data_dir);
      if (!train.empty()) {
        svm = ctxfuse::studies::train_svm_on_cases(train, settings);
        classifier_kind = "svm-siblings";
        classifier_note = "trained on " + std::to_string(train.size()) + " labelled cases";
      } else {
        // The labelled static set cannot train this SVM: its features are the range rate and
        // the platform's speed, and a static tag has neither.
        classifier_note = "no labelled cases and no --nlos-model: the consistency check alone (R = p2)";
      }
    }
    const nu::NlosClassifier classifier(settings, svm);
    if (ref_path.empty()) {
      const std::string_view names[] = {chosen};
      variants = ctxfuse::studies::run_nlos_uwb_variants(ranges, classifier, settings, names);
    } else {
      variants = ctxfuse::studies::run_nlos_uwb_variants(ranges, classifier, settings);
    }
  } catch (const std::exception& e) {
    err << "ctxfuse run uwb: " << e.what() << '\n';
    return 1;
  }
  const auto chosen_it = std::find_if(variants.begin(), variants.end(), [&](const auto& v) { return v.name == chosen; });
  const auto& track = chosen_it->track;
  out << "uwb on " << in.data_dir.string() << ": " << facts.anchors.size() << " anchors, " << rc.ranges.size() << " ranges, report period "
      << formatted("%.4f s", settings.range_period_s) << ", reports the mean of " << settings.range_average_samples << " ("
      << (o.range_average == "auto" ? facts.averaging_note : "--range-average") << ")\nNLOS classifier: " << classifier_kind << " ("
      << classifier_note << ")\n"
      << formatted("%s: %zu estimates, %zu epochs (%zu left out), %zu ranges attached, %zu accepted, %zu gated, %zu starts, %zu restarts\n",
                   chosen.c_str(), track.estimates.size(), track.epochs, track.epochs_left_out, track.ranges_attached,
                   track.ranges_accepted, track.ranges_gated, track.starts, track.restarts);

  Json doc;
  doc["pipeline_name"] = "uwb";
  doc["data"] = in.data_dir.string();
  doc["trajectory_variant"] = chosen;
  doc["estimates"] = static_cast<double>(track.estimates.size());
  doc["nlos_classifier"] = classifier_kind;
  doc["nlos_classifier_note"] = classifier_note;
  doc["svm"] = svm.has_value();
  if (svm) doc["svm_gamma"] = svm->gamma;
  Json cases = Json::array();
  if (classifier_kind == "svm-siblings")
    for (const auto& c : train) cases.push_back(c.string());
  doc["training_cases"] = std::move(cases);
  doc["recording"] = recording_json(rc, facts);
  Json& js = doc["settings"];
  js["range_period_s"] = settings.range_period_s;
  js["epoch_window_s"] = settings.epoch_window_s;
  js["range_average_samples"] = settings.range_average_samples;
  js["range_average_source"] = o.range_average == "auto" ? "detected" : "option";
  js["tag_height_m"] = settings.tag_height_m;
  js["tag_height_source"] = tag_height_source;
  js["tag_height_fit_m"] = facts.tag_height_m;  // null without a fit
  js["tag_height_fit_vertical_sigma_m"] = facts.tag_height_vdop * settings.range_sigma_m;
  js["smoothed_output_lag_s"] = settings.smoothed_output_lag_s;
  js["lag_records_needed"] = nu::lag_records_needed(facts, settings);
  js["lag_records"] = settings.lag_records;
  doc["run"] = track_json(track);

  // --- Scoring, when there is a reference ------------------------------------------------------
  std::optional<UwbScoring> scoring;
  if (!ref_path.empty()) {
    try {
      UwbScoring sc;
      sc.reference = io::read_hanyang_reference_file(ref_path);
      sc.protocol = ctxfuse::studies::choose_protocol(o.span, sc.reference);
      ctxfuse::studies::score_nlos_uwb_variants(variants, sc.reference, sc.protocol);
      scoring = std::move(sc);
    } catch (const std::exception& e) {
      err << "ctxfuse run uwb: warning: not scored: " << e.what() << '\n';
      doc["scoring"]["warning"] = std::string("not scored: ") + e.what();
    }
  }
  if (scoring) {
    const auto& p = scoring->protocol;
    if (!p.warning.empty()) err << "ctxfuse run uwb: warning: " << p.warning << '\n';
    out << "2-D RMSE against " << ref_path.string() << ", "
        << (p.span ? "authors' protocol, span " + p.name + " (" + ctxfuse::studies::describe(p.span->start) + " to " + ctxfuse::studies::describe(p.span->end) + ")"
                   : std::string("whole run"))
        << " (m):\n";
    Json rmse, epochs;
    for (const auto& v : variants) {
      out << formatted("  %-36s %7.3f  (%zu estimates scored, %zu epochs left out)\n", v.name.c_str(), v.rmse.rmse_2d, v.rmse.scored,
                       v.track.epochs_left_out);
      rmse[v.name] = v.rmse.rmse_2d;
      epochs[v.name] = static_cast<double>(v.track.epochs_left_out);
    }
    std::map<std::string, double> authors_rmsd;
    if (std::filesystem::exists(in.data_dir / "RMSD_results.txt")) {
      try {
        authors_rmsd = ctxfuse::studies::read_hanyang_rmsd(in.data_dir / "RMSD_results.txt");
      } catch (const std::exception& e) {
        err << "ctxfuse run uwb: warning: " << e.what() << '\n';
      }
    }
    Json authors;
    for (const char* who : {"LS", "ESKF"})
      if (const auto it = authors_rmsd.find(std::string(who) + " RMSE_2d"); it != authors_rmsd.end()) {
        out << formatted("  authors %-28s %7.3f\n", who, it->second);
        authors[who] = it->second;
      }
    const auto id = ctxfuse::studies::identification(variants.front().track, scoring->reference, settings);
    out << "NLOS identification against residual labels (" << variants.front().name << " run): precision / recall / accuracy\n";
    for (const auto& [name, m] : {std::pair{"svm", id.svm}, std::pair{"consistency", id.consistency}, std::pair{"ds", id.ds}})
      out << formatted("  %-12s %.3f / %.3f / %.3f  (%zu ranges, %zu NLOS)\n", name, m.precision, m.recall, m.accuracy, m.scored,
                       m.labelled_nlos);
    Json& s = doc["scoring"];
    s["reference"] = ref_path.string();
    s["protocol"] = p.name;
    if (p.span) s["span"] = ctxfuse::studies::describe(p.span->start) + "/" + ctxfuse::studies::describe(p.span->end);
    s["warning"] = p.warning;
    s["t_begin"] = chosen_it->rmse.t_begin;
    s["t_end"] = chosen_it->rmse.t_end;
    s["scored"] = static_cast<double>(chosen_it->rmse.scored);
    doc["rmse_2d_m"] = std::move(rmse);
    doc["epochs_left_out"] = std::move(epochs);
    doc["authors_rmse_2d_m"] = std::move(authors);
    doc["identification"]["svm"] = identification_json(id.svm);
    doc["identification"]["consistency"] = identification_json(id.consistency);
    doc["identification"]["ds"] = identification_json(id.ds);
  }

  if (!in.out_csv.empty() && !write_trajectory(in.out_csv, track, settings.tag_height_m, err)) return 1;
  if (!in.json.empty() && !write_json_file(doc, in.json, "run uwb", err)) return 1;
  if (!o.save_nlos_model.empty()) {
    if (!svm) {
      err << "ctxfuse run uwb: --save-nlos-model: this run has no SVM (" << classifier_note << ")\n";
      return 1;
    }
    try {
      classify::save_svm_model(o.save_nlos_model, *svm);
    } catch (const std::exception& e) {
      err << "ctxfuse run uwb: --save-nlos-model: " << e.what() << '\n';
      return 1;
    }
  }
  if (!in.plot.empty()) {
    try {
      plot_case(in.plot, variants, chosen, in.data_dir, scoring ? &*scoring : nullptr, out, err);
    } catch (const std::exception& e) {
      err << "ctxfuse run uwb: plots: " << e.what() << '\n';
      return 1;
    }
  }
  return 0;
}

const RegisterRunPipeline reg_run_uwb{
    {"uwb", "NLOS-robust UWB (paper C) on a folder of per-anchor ranges, with its baselines when scored",
     "A<id>.csv per anchor, nothing else (a reference, --reference or trajectory.csv, to score; labelled cases, "
     "--nlos-model or the dataset's other cases, for the NLOS SVM)",
     add_options, {}, run_uwb}};

}  // namespace
}  // namespace ctxfuse::cli

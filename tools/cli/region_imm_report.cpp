// The region report and the region pipeline's entry points (cli/region_imm_report.hpp), in
// one source so that the tool compiles them once.
#include "cli/region_imm_report.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "cli/formatted.hpp"
#include "ctxfuse/instances/region_imm.hpp"  // run() compiled once (ctxfuse::instances)
#include "ctxfuse/eval/region_errors.hpp"
#include "ctxfuse/studies/region_training.hpp"

namespace ctxfuse::cli {

ri::RunResult run_region_pipeline(const messages::SensorLog& log, ri::Estimator e, const ri::Settings& s, const ri::RunOptions& o) {
  return ri::run(log, e, s, o);
}

ri::Recogniser train_region_recogniser(const sim::DriveConfig& test) { return ctxfuse::studies::train_recogniser_for(test); }

ri::Recogniser train_region_recogniser(std::span<const ri::LabelledFeatures> train, const ri::LabelledFeatures& validate) {
  return ri::train_recogniser(train, validate);
}

namespace region_report {

struct PaperRow {
  const char* label;
  ri::Estimator estimator;
  std::array<double, 4> mean;  // outdoor, transition, indoor, overall (m)
};

// Paper A, tables 3 and 4 (mean position error, m).
inline constexpr std::array<PaperRow, 8> kPaperMean{{
    {"GNSS", ri::Estimator::gnss, {1.94, 1.71, 6.63, 4.16}},
    {"UWB", ri::Estimator::uwb, {5.88, 3.10, 0.54, 2.85}},
    {"EKF-ODR", ri::Estimator::odr, {1.90, 1.70, 5.90, 3.74}},
    {"EKF-I-OTR", ri::Estimator::iotr, {1.66, 1.16, 1.32, 1.41}},
    {"EKF-IDR", ri::Estimator::idr, {5.79, 3.09, 0.44, 2.82}},
    {"FKF", ri::Estimator::fkf, {1.79, 1.52, 2.18, 1.92}},
    {"IMM", ri::Estimator::imm, {1.66, 1.04, 1.33, 1.39}},
    {"region IMM", ri::Estimator::region_imm, {1.94, 0.91, 0.53, 1.08}},
}};
// Tables 5 and 6 (RMSE X, Y in m) for FKF, IMM, proposed.
inline constexpr std::array<std::array<double, 4>, 3> kPaperRmseX{{{1.22, 1.29, 0.83, 1.05}, {1.24, 1.22, 0.53, 0.91}, {1.23, 1.36, 0.26, 0.80}}};
inline constexpr std::array<std::array<double, 4>, 3> kPaperRmseY{{{1.72, 1.80, 2.18, 1.87}, {1.50, 0.89, 1.19, 1.16}, {1.28, 0.49, 0.42, 0.88}}};
inline constexpr std::array<const char*, 4> kColumn{"outdoor", "transition", "indoor", "overall"};

inline void set_row(Json& json, const std::string& prefix, const std::array<double, 4>& v) {
  for (std::size_t k = 0; k < 4; ++k) json.set(prefix + "." + kColumn[k], v[k]);
}

}  // namespace region_report

/// Prints the tables to `out` and fills `json` (the keys of docs/formats.md, "region_imm");
/// returns the region IMM's track.
ri::Track region_imm_report(const RegionImmRun& in, Json& json, std::ostream& out) {
  using namespace region_report;
  const auto& truth = in.truth.truth;
  const ri::Recogniser& rec = in.recogniser;

  // ---- Table 2: recognition, against the true region at each receiver epoch.
  const auto features = ri::gnss_features(in.log.sat_epochs);
  const auto labels = eval::region_labels(truth, features.t);
  // The paper's table: the HMM's Viterbi path over the whole log (offline), which the navigation
  // below also runs on; the causal recognition (forward filter) is reported beside it.
  const ri::Recognition r = ri::recognise(rec, features);
  const ri::Recognition causal = ri::recognise_causal(rec, features);
  const double acc_svm = ri::accuracy(labels, r.svm), acc_hmm = ri::accuracy(labels, r.hmm), acc_joint = ri::accuracy(labels, r.joint);
  const double acc_hmm_causal = ri::accuracy(labels, causal.hmm), acc_joint_causal = ri::accuracy(labels, causal.joint);
  out << "Region recognition (" << features.x.size() << " receiver epochs; " << in.recogniser_note << "; PSO-SVM C="
      << formatted("%.3g, gamma=%.3g", rec.tuned.C, rec.tuned.gamma) << ", CV score " << formatted("%.2f %%", 100.0 * rec.tuned.cv_accuracy) << ")\n";
  out << "  classifier   paper    ours (offline: Viterbi)   ours (causal: forward filter)\n";
  out << "  PSO-SVM    " << formatted("%6.2f %%  %6.2f %%                  %6.2f %%\n", 95.96, 100.0 * acc_svm, 100.0 * acc_svm);
  out << "  HMM        " << formatted("%6.2f %%  %6.2f %%                  %6.2f %%\n", 88.56, 100.0 * acc_hmm, 100.0 * acc_hmm_causal);
  out << "  joint      " << formatted("%6.2f %%  %6.2f %%                  %6.2f %%\n", 98.09, 100.0 * acc_joint, 100.0 * acc_joint_causal);
  json.set("recognition_accuracy.svm", acc_svm);
  json.set("recognition_accuracy.hmm", acc_hmm);
  json.set("recognition_accuracy.joint", acc_joint);
  json.set("recognition_accuracy.hmm_causal", acc_hmm_causal);
  json.set("recognition_accuracy.joint_causal", acc_joint_causal);
  json.set("recognition.svm_C", rec.tuned.C);
  json.set("recognition.svm_gamma", rec.tuned.gamma);

  // ---- Tables 3-6: navigation.
  const ri::Settings settings;
  const auto regions = ri::region_track(features, r.joint, ri::hmm_posteriors(rec, features));
  const auto true_regions = ri::region_track(features, labels);
  ri::RunOptions options;
  options.regions = &regions;
  std::array<ri::RunResult, 8> runs;
  std::array<eval::TrackErrors, 8> errs;
  for (std::size_t i = 0; i < kPaperMean.size(); ++i) {
    runs[i] = ri::run(in.log, kPaperMean[i].estimator, settings, options);
    errs[i] = eval::region_errors(runs[i].track, truth);
  }
  if (runs[0].alignment) {
    const auto& a = *runs[0].alignment;
    constexpr double deg = 180.0 / std::numbers::pi;
    out << formatted("Start: dynamic alignment at t = %.1f s (heading %.1f +/- %.1f deg from two fixes)\n", a.t, a.heading * deg,
               std::sqrt(a.heading_var) * deg);
    json.set("start.t_s", a.t);
    json.set("start.heading_deg", a.heading * deg);
  }
  if (in.plotter) {
    // FKF, plain IMM and region IMM (rows 5-7) against the truth, and their error CDFs.
    const auto at = eval::truth_at(runs[7].track.t, truth);
    std::vector<Plotter::Series> series{{"truth", at.position, true}};
    std::vector<std::pair<std::string, std::vector<double>>> cdf;
    for (std::size_t i : {5u, 6u, 7u}) {
      const auto& tr = runs[i].track;
      std::vector<double> e;
      for (std::size_t k = 0; k < tr.t.size(); ++k) e.push_back((tr.estimate[k] - at.position[k]).norm());
      series.push_back({kPaperMean[i].label, tr.estimate, true});
      cdf.emplace_back(kPaperMean[i].label, std::move(e));
    }
    in.plotter->trajectory("region_imm_trajectory", "Region IMM, plain IMM and FKF against the truth (1 Hz)", series);
    in.plotter->error_cdf("region_imm_error_cdf", "Horizontal error CDF: FKF, IMM, region IMM", cdf);
  }
  // The region IMM fed the true labels (how much recognition errors cost), and the extension:
  // its matrix also pulled towards the HMM's causal region posterior.
  ri::RunOptions oracle_options;
  oracle_options.regions = &true_regions;
  const auto oracle = eval::region_errors(ri::run(in.log, ri::Estimator::region_imm, settings, oracle_options).track, truth);
  const auto pulled = eval::region_errors(ri::run(in.log, ri::Estimator::region_imm_posterior, settings, options).track, truth);
  // The paper's FKF as its text describes it: fixed fusion weights (our FKF row fuses by
  // information, which makes it a centralised filter for these models).
  const auto fkf_static = eval::region_errors(ri::run(in.log, ri::Estimator::fkf_static, settings, options).track, truth);
  out << "Mean horizontal position error (m), paper | ours, per true region (scored at " << errs[0].count[3] << " receiver epochs)\n";
  out << "  method         outdoor       transition    indoor        overall\n";
  for (std::size_t i = 0; i < kPaperMean.size(); ++i) {
    out << formatted("  %-12s", kPaperMean[i].label);
    for (std::size_t k = 0; k < 4; ++k) out << formatted("  %5.2f|%5.2f ", kPaperMean[i].mean[k], errs[i].mean[k]);
    out << "\n";
    set_row(json, std::string("mean_error_m.") + ri::name(kPaperMean[i].estimator), errs[i].mean);
  }
  out << "  (true labels)";
  for (std::size_t k = 0; k < 4; ++k) out << formatted("   --  |%5.2f ", oracle.mean[k]);
  out << "\n";
  set_row(json, "mean_error_m.region_imm_true_labels", oracle.mean);
  out << "  (FKF static) ";
  for (std::size_t k = 0; k < 4; ++k) out << formatted("   --  |%5.2f ", fkf_static.mean[k]);
  out << "   FKF with fixed fusion weights beta_i (the paper's reading)\n";
  set_row(json, "mean_error_m.fkf_static", fkf_static.mean);
  out << formatted("  (+ pull %.1f)", settings.posterior_pull);
  for (std::size_t k = 0; k < 4; ++k) out << formatted("   --  |%5.2f ", pulled.mean[k]);
  out << "   region IMM + HMM posterior pull (extension)\n";
  set_row(json, "mean_error_m.region_imm_posterior", pulled.mean);
  // The rows above score a single sensor without a solution at the position it holds; here
  // only where it has one, with the share of epochs it covers (the paper does not say how it
  // scored the epochs without one).
  out << "  single sensors where they have a solution: mean error (m) / share of epochs\n";
  for (std::size_t i : {0u, 1u}) {
    out << formatted("  %-12s", kPaperMean[i].label);
    for (std::size_t k = 0; k < 4; ++k) {
      const double m = errs[i].mean_with_solution[k], a = errs[i].availability(k);
      out << (errs[i].with_solution[k] ? formatted("  %5.2f/%3.0f%%", m, 100.0 * a) : formatted("     --/%3.0f%%", 100.0 * a));
      json.set(std::string("mean_error_with_solution_m.") + ri::name(kPaperMean[i].estimator) + "." + kColumn[k], m);
      json.set(std::string("availability.") + ri::name(kPaperMean[i].estimator) + "." + kColumn[k], a);
    }
    out << "\n";
  }
  const std::array<std::size_t, 3> rmse_rows{5, 6, 7};
  for (int axis = 0; axis < 2; ++axis) {
    out << (axis == 0 ? "X" : "Y") << " RMSE (m), paper | ours\n";
    for (std::size_t k = 0; k < 3; ++k) {
      const std::size_t i = rmse_rows[k];
      out << formatted("  %-12s", kPaperMean[i].label);
      const auto& paper = axis == 0 ? kPaperRmseX[k] : kPaperRmseY[k];
      const auto& ours = axis == 0 ? errs[i].rmse_x : errs[i].rmse_y;
      for (std::size_t c = 0; c < 4; ++c) out << formatted("  %5.2f|%5.2f ", paper[c], ours[c]);
      out << "\n";
      set_row(json, std::string(axis == 0 ? "rmse_x_m." : "rmse_y_m.") + ri::name(kPaperMean[i].estimator), ours);
    }
  }
  const double fkf = errs[5].mean[3], imm = errs[6].mean[3], prop = errs[7].mean[3];
  const bool order_overall = prop < imm && imm < fkf;
  const bool order_transition = errs[7].mean[1] < errs[6].mean[1] && errs[6].mean[1] < errs[5].mean[1];
  const bool order_recognition = acc_joint > acc_svm && acc_svm > acc_hmm;
  out << "Paper's ordering: region IMM < IMM < FKF overall: " << (order_overall ? "holds" : "does NOT hold")
      << "; in the transition region: " << (order_transition ? "holds" : "does NOT hold")
      << "; recognition joint > SVM > HMM: " << (order_recognition ? "holds" : "does NOT hold") << "\n";
  out << formatted("  overall improvement of region IMM over FKF %.1f %% (paper 43.75 %%), over IMM %.1f %% (paper 22.30 %%)\n",
             100.0 * (fkf - prop) / fkf, 100.0 * (imm - prop) / imm);
  // What routing can act on: it keeps UWB from the sub-models outdoors and GNSS indoors, so
  // it can only matter where the log has UWB ranges outdoors or GNSS fixes indoors.
  std::array<int, 3> epochs{}, uwb_epochs{}, fix_epochs{};
  {
    std::size_t w = 0, g = 0;
    const auto& uwb = in.log.uwb;
    const auto& fixes = in.log.gnss;
    for (std::size_t i = 0; i < features.t.size(); ++i) {
      const double t = features.t[i];
      const auto region = static_cast<std::size_t>(labels[i]);
      ++epochs[region];
      while (g < fixes.size() && fixes[g].t < t) ++g;
      fix_epochs[region] += g < fixes.size() && fixes[g].t == t ? 1 : 0;
      bool ranged = false;
      for (; w < uwb.size() && uwb[w].t <= t + 1e-9; ++w) ranged |= uwb[w].t > t - 1.0 + 1e-9;
      uwb_epochs[region] += ranged;
    }
  }
  out << "  what routing can exclude: UWB ranges at " << uwb_epochs[0] << " of " << epochs[0] << " outdoor epochs, GNSS fixes at "
      << fix_epochs[2] << " of " << epochs[2] << " indoor epochs\n";
  // The UWB integrity check (Settings::uwb_integrity): how often it re-anchored each filter.
  out << "  UWB integrity re-anchorings:";
  for (std::size_t i = 0; i < kPaperMean.size(); ++i) {
    const auto e = kPaperMean[i].estimator;
    if (e == ri::Estimator::gnss || e == ri::Estimator::uwb || e == ri::Estimator::odr) continue;
    out << ' ' << kPaperMean[i].label << ' ' << runs[i].track.integrity_faults;
    json.set(std::string("integrity_faults.") + ri::name(e), runs[i].track.integrity_faults);
  }
  out << '\n';
  json.set("routing.outdoor_epochs_with_uwb", uwb_epochs[0]);
  json.set("routing.indoor_epochs_with_gnss_fix", fix_epochs[2]);
  json.set("ordering.overall_holds", order_overall);
  json.set("ordering.transition_holds", order_transition);
  json.set("ordering.recognition_holds", order_recognition);
  return runs[7].track;
}

}  // namespace ctxfuse::cli

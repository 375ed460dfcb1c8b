// `ctxfuse demo` section "region_imm": the region paper's tables 2-5/6 (recognition accuracy;
// mean error per region of the single sensors, single sub-models, FKF, plain IMM and the
// region-aware IMM; X/Y RMSE) with ours side by side, on the simulated drive.
// Training and validation of the recogniser use other simulated drives (training: seeds
// + 101, + 102 and + 103; validation: seed + 202), the test is the demo drive, as the paper
// trains, validates and tests on separate data.
#include <array>
#include <cstdint>
#include <cstdio>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "cli/plot.hpp"
#include "cli/registry.hpp"
#include "ctxfuse/pipelines/region_imm.hpp"
#include "ctxfuse/sim/drive.hpp"

namespace ctxfuse::cli {
namespace {

namespace ri = pipelines::region_imm;

struct PaperRow {
  const char* label;
  ri::Estimator estimator;
  std::array<double, 4> mean;  // outdoor, transition, indoor, overall (m)
};

// Paper A, tables 3 and 4 (mean position error, m).
constexpr std::array<PaperRow, 8> kPaperMean{{
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
constexpr std::array<std::array<double, 4>, 3> kPaperRmseX{{{1.22, 1.29, 0.83, 1.05}, {1.24, 1.22, 0.53, 0.91}, {1.23, 1.36, 0.26, 0.80}}};
constexpr std::array<std::array<double, 4>, 3> kPaperRmseY{{{1.72, 1.80, 2.18, 1.87}, {1.50, 0.89, 1.19, 1.16}, {1.28, 0.49, 0.42, 0.88}}};
constexpr std::array<const char*, 4> kColumn{"outdoor", "transition", "indoor", "overall"};

std::string fmt(const char* f, double a, double b) {
  char buf[256];
  std::snprintf(buf, sizeof buf, f, a, b);
  return buf;
}

std::string fmt1(const char* f, double a) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, a);
  return buf;
}

void run_section(const DemoContext& ctx, Json& json, std::ostream& out) {
  const sim::Drive& test = *ctx.drive;
  using Drives = ri::TrainingDrives;

  // ---- Table 2: recognition.
  const auto f_test = ri::gnss_features(test);
  const ri::Recogniser rec = ri::train_recogniser_for(test);
  const ri::Recognition r = ri::recognise(rec, f_test);
  const double acc_svm = ri::accuracy(f_test.truth, r.svm), acc_hmm = ri::accuracy(f_test.truth, r.hmm),
               acc_joint = ri::accuracy(f_test.truth, r.joint);
  out << "Region recognition on the demo drive (" << f_test.x.size() << " GNSS epochs; trained on seeds " << test.config.seed + Drives::train_seed_offset
      << "-" << test.config.seed + Drives::train_seed_offset + Drives::train_drives - 1 << ", validated on seed "
      << test.config.seed + Drives::validate_seed_offset << "; PSO-SVM C=" << fmt("%.3g, gamma=%.3g", rec.tuned.C, rec.tuned.gamma)
      << ", CV accuracy " << fmt1("%.2f %%", 100.0 * rec.tuned.cv_accuracy) << ")\n";
  out << "  classifier   paper    ours\n";
  out << "  PSO-SVM    " << fmt("%6.2f %%  %6.2f %%\n", 95.96, 100.0 * acc_svm);
  out << "  HMM        " << fmt("%6.2f %%  %6.2f %%\n", 88.56, 100.0 * acc_hmm);
  out << "  joint      " << fmt("%6.2f %%  %6.2f %%\n", 98.09, 100.0 * acc_joint);
  json.set("recognition_accuracy.svm", acc_svm);
  json.set("recognition_accuracy.hmm", acc_hmm);
  json.set("recognition_accuracy.joint", acc_joint);
  json.set("recognition.svm_C", rec.tuned.C);
  json.set("recognition.svm_gamma", rec.tuned.gamma);

  // ---- Tables 3-6: navigation.
  const ri::Settings settings;
  std::array<ri::TrackErrors, 8> errs;
  std::array<ri::Track, 8> tracks;
  for (std::size_t i = 0; i < kPaperMean.size(); ++i) {
    tracks[i] = ri::run(test, kPaperMean[i].estimator, settings, &r.joint);
    errs[i] = ri::errors(tracks[i]);
  }
  if (ctx.plotter) {
    // FKF, plain IMM and region IMM (rows 5-7) against the truth, and their error CDFs.
    Plotter::Series truth{"truth", {}, true};
    for (const auto& p : tracks[7].truth) truth.points.push_back(p);
    std::vector<Plotter::Series> series{truth};
    std::vector<std::pair<std::string, std::vector<double>>> cdf;
    for (std::size_t i : {5u, 6u, 7u}) {
      Plotter::Series s{kPaperMean[i].label, {}, true};
      std::vector<double> e;
      for (std::size_t k = 0; k < tracks[i].t.size(); ++k) {
        s.points.push_back(tracks[i].estimate[k]);
        e.push_back((tracks[i].estimate[k] - tracks[i].truth[k]).norm());
      }
      series.push_back(std::move(s));
      cdf.emplace_back(kPaperMean[i].label, std::move(e));
    }
    ctx.plotter->trajectory("region_imm_trajectory", "Region IMM, plain IMM and FKF against the truth (1 Hz)", series);
    ctx.plotter->error_cdf("region_imm_error_cdf", "Horizontal error CDF: FKF, IMM, region IMM", cdf);
  }
  ri::TrackErrors oracle;  // region IMM fed the true labels: how much recognition errors cost
  {
    const auto tr = ri::run(test, ri::Estimator::region_imm, settings, &f_test.truth);
    oracle = ri::errors(tr);
  }
  // Extension: the region IMM's matrix also pulled towards the HMM's causal region posterior.
  const auto posteriors = ri::hmm_posteriors(rec, f_test);
  const ri::TrackErrors pulled =
      ri::errors(ri::run(test, ri::Estimator::region_imm_posterior, settings, &r.joint, &posteriors));
  out << "Mean horizontal position error (m), paper | ours, per true region (scored at " << errs[0].count[3]
      << " GNSS epochs)\n";
  out << "  method         outdoor       transition    indoor        overall\n";
  for (std::size_t i = 0; i < kPaperMean.size(); ++i) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "  %-12s", kPaperMean[i].label);
    out << buf;
    for (int k = 0; k < 4; ++k) out << fmt("  %5.2f|%5.2f ", kPaperMean[i].mean[static_cast<std::size_t>(k)], errs[i].mean[static_cast<std::size_t>(k)]);
    out << "\n";
    for (int k = 0; k < 4; ++k)
      json.set(std::string("mean_error_m.") + ri::name(kPaperMean[i].estimator) + "." + kColumn[static_cast<std::size_t>(k)],
               errs[i].mean[static_cast<std::size_t>(k)]);
  }
  {
    out << "  (true labels)";
    for (int k = 0; k < 4; ++k) out << fmt1("   --  |%5.2f ", oracle.mean[static_cast<std::size_t>(k)]);
    out << "\n";
    for (int k = 0; k < 4; ++k)
      json.set(std::string("mean_error_m.region_imm_true_labels.") + kColumn[static_cast<std::size_t>(k)], oracle.mean[static_cast<std::size_t>(k)]);
  }
  {
    out << fmt1("  (+ pull %.1f)", settings.posterior_pull);
    for (int k = 0; k < 4; ++k) out << fmt1("   --  |%5.2f ", pulled.mean[static_cast<std::size_t>(k)]);
    out << "   region IMM + HMM posterior pull (extension)\n";
    for (int k = 0; k < 4; ++k)
      json.set(std::string("mean_error_m.region_imm_posterior.") + kColumn[static_cast<std::size_t>(k)], pulled.mean[static_cast<std::size_t>(k)]);
  }
  // The rows above score a single sensor without a solution at the position it holds; here
  // only where it has one, with the share of epochs it covers (the paper does not say how it
  // scored the epochs without one).
  out << "  single sensors where they have a solution: mean error (m) / share of epochs\n";
  for (std::size_t i : {0u, 1u}) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "  %-12s", kPaperMean[i].label);
    out << buf;
    for (std::size_t k = 0; k < 4; ++k) {
      const double m = errs[i].mean_with_solution[k], a = errs[i].availability(k);
      out << (errs[i].with_solution[k] ? fmt("  %5.2f/%3.0f%%", m, 100.0 * a) : fmt1("     --/%3.0f%%", 100.0 * a));
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
      char buf[64];
      std::snprintf(buf, sizeof buf, "  %-12s", kPaperMean[i].label);
      out << buf;
      const auto& paper = axis == 0 ? kPaperRmseX[k] : kPaperRmseY[k];
      const auto& ours = axis == 0 ? errs[i].rmse_x : errs[i].rmse_y;
      for (int c = 0; c < 4; ++c) out << fmt("  %5.2f|%5.2f ", paper[static_cast<std::size_t>(c)], ours[static_cast<std::size_t>(c)]);
      out << "\n";
      for (int c = 0; c < 4; ++c)
        json.set(std::string(axis == 0 ? "rmse_x_m." : "rmse_y_m.") + ri::name(kPaperMean[i].estimator) + "." + kColumn[static_cast<std::size_t>(c)],
                 ours[static_cast<std::size_t>(c)]);
    }
  }
  const double fkf = errs[5].mean[3], imm = errs[6].mean[3], prop = errs[7].mean[3];
  const bool order_overall = prop < imm && imm < fkf;
  const bool order_transition = errs[7].mean[1] < errs[6].mean[1] && errs[6].mean[1] < errs[5].mean[1];
  const bool order_recognition = acc_joint > acc_svm && acc_svm > acc_hmm;
  out << "Paper's ordering: region IMM < IMM < FKF overall: " << (order_overall ? "holds" : "does NOT hold")
      << "; in the transition region: " << (order_transition ? "holds" : "does NOT hold")
      << "; recognition joint > SVM > HMM: " << (order_recognition ? "holds" : "does NOT hold") << "\n";
  out << fmt("  overall improvement of region IMM over FKF %.1f %% (paper 43.75 %%), over IMM %.1f %% (paper 22.30 %%)\n",
             100.0 * (fkf - prop) / fkf, 100.0 * (imm - prop) / imm);
  // What routing can act on: it keeps UWB from the sub-models outdoors and GNSS indoors, so
  // it can only matter where the drive has UWB ranges outdoors or GNSS fixes indoors.
  std::array<int, 3> epochs{}, uwb_epochs{}, fix_epochs{};
  {
    std::size_t w = 0;
    for (const auto& e : test.gnss) {
      const auto region = static_cast<std::size_t>(e.region);
      ++epochs[region];
      fix_epochs[region] += e.has_fix;
      bool ranged = false;
      for (; w < test.uwb.size() && test.uwb[w].t <= e.t + 1e-9; ++w) ranged |= test.uwb[w].t > e.t - 1.0 + 1e-9;
      uwb_epochs[region] += ranged;
    }
  }
  out << "  what routing can exclude: UWB ranges at " << uwb_epochs[0] << " of " << epochs[0]
      << " outdoor epochs, GNSS fixes at " << fix_epochs[2] << " of " << epochs[2] << " indoor epochs\n";
  // The UWB integrity check (Settings::uwb_integrity): how often it re-anchored each filter.
  out << "  UWB integrity re-anchorings:";
  for (std::size_t i = 0; i < kPaperMean.size(); ++i) {
    const auto e = kPaperMean[i].estimator;
    if (e == ri::Estimator::gnss || e == ri::Estimator::uwb || e == ri::Estimator::odr) continue;
    out << ' ' << kPaperMean[i].label << ' ' << tracks[i].integrity_faults;
    json.set(std::string("integrity_faults.") + ri::name(e), tracks[i].integrity_faults);
  }
  out << '\n';
  json.set("routing.outdoor_epochs_with_uwb", uwb_epochs[0]);
  json.set("routing.indoor_epochs_with_gnss_fix", fix_epochs[2]);
  json.set("ordering.overall_holds", order_overall);
  json.set("ordering.transition_holds", order_transition);
  json.set("ordering.recognition_holds", order_recognition);
}

const RegisterDemoSection reg{{"region_imm", "Region-aware IMM, seamless indoor/outdoor (paper A)", run_section}};

}  // namespace
}  // namespace ctxfuse::cli

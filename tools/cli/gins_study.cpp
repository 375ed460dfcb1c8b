// `ctxfuse gins-study`: the papers' GNSS/INS schemes on simulated drives (studies/gins_sim_study.hpp):
// (a) GNSS/INS, (b) + RTS, (c) + constraints, (d) + both, with ZIHR as extra rows, each with a
// fixed GNSS R, the scene-adaptive R from the trained scene classifier, and the scene-adaptive
// R from the true scenes (oracle). Horizontal error at the 1 Hz truth epochs: RMS, 67 %, 75 %,
// max, over the whole drive and split into the part with GNSS and the garage (no fix).
// docs/results.md (section gins_sim) quotes it; every printed number is also in --json.
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "cli/formatted.hpp"
#include "cli/gins_study.hpp"
#include "cli/json.hpp"
#include "cli/options.hpp"
#include "cli/registry.hpp"
#include "cli/seed_list.hpp"
#include "ctxfuse/instances/gins_sim_study.hpp"
#include "ctxfuse/sim/drive.hpp"

namespace ctxfuse::cli {

ctxfuse::studies::GinsSimStudy gins_study_of(const sim::Drive& drive, const ctxfuse::studies::GinsSimSettings& settings) {
  return ctxfuse::studies::gins_sim_study(drive, settings);
}

namespace {

int gins_study(Args args, std::ostream& out, std::ostream& err) {
  CLI::App app = make_app(
      "gins-study",
      "GNSS/INS schemes of the scene paper (B) and the smartphone paper (D) on simulated drives: (a) GNSS/INS,\n"
      "(b) + RTS, (c) + ZUPT/NHC with odometer speed, (d) + both (and with ZIHR), each with fixed R (2 m),\n"
      "scene-adaptive R (eq. 20-21) from the linear SVM trained on seeds N+101..N+103, and from the true scenes.");
  std::string seeds_text = "1", json_file;
  app.add_option("--seeds", seeds_text, "seeds, e.g. 1-5, 1,3,7 or 1-3,9");
  app.add_option("--json", json_file, "every printed number also as JSON");
  ctxfuse::studies::GinsSimSettings settings;
  double speed_scale_sigma = -1.0;
  app.add_option("--speed-scale-sigma", speed_scale_sigma,
                 "prior sigma of the odometer's scale error (default: its data sheet, 0.01); 0: not estimated (15 states)")
      ->check(CLI::NonNegativeNumber);
  int gate_release = settings.gate_release.min_rejections;
  app.add_option("--gate-release", gate_release,
                 "fixes refused in a row after which the next is released (the GNSS/INS pipeline's 3); 0: never")
      ->check(CLI::NonNegativeNumber);
  if (const auto rc = parse_options(app, args, out, err)) return *rc;
  settings.gate_release.min_rejections = gate_release > 0 ? gate_release : std::numeric_limits<int>::max();
  std::vector<std::uint64_t> seeds;
  if (!parse_seeds(seeds_text, seeds, err)) return 2;
  if (speed_scale_sigma >= 0.0) settings.speed_scale_sigma = speed_scale_sigma;
  const std::optional<std::string> json_path = json_file.empty() ? std::nullopt : std::optional<std::string>(json_file);
  if (json_path && !write_json_file(Json{}, *json_path, "gins-study", err)) return 1;

  Json doc;
  Json per_seed = Json::array();
  std::map<std::string, std::vector<double>> sums;  // key -> {rms, p67, p75, max, rms_gnss, rms_indoor}
  std::vector<std::string> order;
  for (const std::uint64_t seed : seeds) {
    sim::DriveConfig cfg;
    cfg.seed = seed;
    const ctxfuse::studies::GinsSimStudy st = gins_study_of(sim::simulate_drive(cfg), settings);
    out << formatted("\n=== seed %llu: %zu IMU samples, %zu fixes; scene classifier accuracy %.2f %%; static while moving: "
                     "IMU detector %.2f %%, with the odometer %.2f %% of moving samples; odometer scale error drawn %+.4f\n",
                     static_cast<unsigned long long>(seed), st.imu_samples, st.fixes, 100.0 * st.scene_accuracy,
                     100.0 * st.false_static_share, 100.0 * st.false_static_share_odometer, st.speed_scale_truth);
    out << "  scheme                              | R                  | RMS     67 %    75 %    max     | RMS GNSS  RMS garage | fixes used/gated/released | odometer scale (1 sigma)\n";
    Json j;
    j["seed"] = static_cast<double>(seed);
    j["scene_accuracy"] = st.scene_accuracy;
    j["false_static_share"] = st.false_static_share;
    j["false_static_share_odometer"] = st.false_static_share_odometer;
    j["imu_samples"] = static_cast<double>(st.imu_samples);
    j["fixes"] = static_cast<double>(st.fixes);
    j["speed_scale_truth"] = st.speed_scale_truth;
    Json runs = Json::array();
    for (const auto& r : st.runs) {
      out << formatted("  %-35s | %-18s | %-7.2f %-7.2f %-7.2f %-7.2f | %-9.2f %-10.2f | %-25s | %+.4f (%.4f)\n",
                       r.scheme.name.c_str(), r.noise.c_str(), r.all.rms, r.all.p67, r.all.p75, r.all.max, r.with_gnss.rms,
                       r.indoor.rms, (std::to_string(r.fixes_used) + "/" + std::to_string(r.fixes_gated) + "/" + std::to_string(r.fixes_released)).c_str(), r.speed_scale,
                       r.speed_scale_sigma);
      if (r.scheme.smooth && !r.smoothed) out << "    RTS refused (a prior covariance not positive definite): the row above is the forward filter's\n";
      Json rj;
      rj["scheme"] = r.scheme.name;
      rj["noise"] = r.noise;
      add_gins_run_json(r, rj);
      rj["rts_bytes"] = static_cast<double>(r.rts_bytes);
      runs.push_back(std::move(rj));
      const std::string key = r.scheme.name + " | " + r.noise;
      auto& s = sums[key];
      if (s.empty()) {
        s.assign(6, 0.0);
        order.push_back(key);
      }
      const double v[6] = {r.all.rms, r.all.p67, r.all.p75, r.all.max, r.with_gnss.rms, r.indoor.rms};
      for (int i = 0; i < 6; ++i) s[static_cast<std::size_t>(i)] += v[i];
    }
    j["runs"] = std::move(runs);
    per_seed.push_back(std::move(j));
    out.flush();
  }
  doc["per_seed"] = std::move(per_seed);
  if (seeds.size() > 1) {
    const double n = static_cast<double>(seeds.size());
    out << formatted("\n=== mean over %zu seeds (%s)\n", seeds.size(), seeds_text.c_str());
    Json mean = Json::array();
    for (const auto& key : order) {
      const auto& s = sums[key];
      out << formatted("  %-56s | %-7.2f %-7.2f %-7.2f %-7.2f | %-9.2f %-10.2f\n", key.c_str(), s[0] / n, s[1] / n, s[2] / n, s[3] / n,
                       s[4] / n, s[5] / n);
      Json m;
      m["key"] = key;
      m["rms_m"] = s[0] / n;
      m["p67_m"] = s[1] / n;
      m["p75_m"] = s[2] / n;
      m["max_m"] = s[3] / n;
      m["rms_with_gnss_m"] = s[4] / n;
      m["rms_indoor_m"] = s[5] / n;
      mean.push_back(std::move(m));
    }
    doc["mean_over_seeds"] = std::move(mean);
  }
  if (json_path && !write_json_file(doc, *json_path, "gins-study", err)) return 1;
  return 0;
}

const RegisterCommand reg_gins_study{{"gins-study", "GNSS/INS schemes (a)-(d), fixed vs scene-adaptive R, on simulated drives (papers B, D)", gins_study}};

}  // namespace
}  // namespace ctxfuse::cli

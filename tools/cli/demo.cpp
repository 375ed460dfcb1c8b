// `ctxfuse demo [--seed N] [--scenario NAME] [--json FILE] [--plot DIR]`: simulates the drive
// (the default scenario unless named; sim/scenarios.hpp), prints
// its summary and the GNSS-alone baseline, then runs every registered demo section in the
// order of the papers (region_imm, scene_gins, nlos_uwb, phone_gins, latency_us).
#include <array>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "cli/options.hpp"
#include "cli/error_report.hpp"
#include "cli/plot.hpp"
#include "cli/progress.hpp"
#include "cli/registry.hpp"
#include "cli/scenario_flag.hpp"
#include "ctxfuse/eval/trajectory.hpp"
#include "ctxfuse/sim/drive.hpp"

namespace ctxfuse::cli {
namespace {

struct SectionSlot {
  std::string_view key;
  std::string_view title;  // shown when the section is not built
};
constexpr std::array<SectionSlot, 5> kSectionOrder{{
    {"region_imm", "Region-aware IMM, seamless indoor/outdoor (paper A)"},
    {"scene_gins", "Scene-adaptive GNSS/INS (paper B)"},
    {"nlos_uwb", "NLOS-robust UWB/IMU (paper C)"},
    {"phone_gins", "Smartphone GNSS/INS with vehicle constraints (paper D)"},
    {"latency_us", "Per-sample latency (paper C, Table 5)"},
}};

void drive_summary(const sim::Drive& d, Json& j, std::ostream& out) {
  const auto shares = d.region_shares();
  const auto& cfg = d.config.route;
  char buf[256];
  std::snprintf(buf, sizeof buf, "Simulated drive (seed %llu): %.1f s, %.0f m; region shares outdoor/transition/indoor %.1f/%.1f/%.1f %% (configured %.1f/%.1f/%.1f)\n",
                static_cast<unsigned long long>(d.config.seed), d.duration(), d.route.length(), 100 * shares[0], 100 * shares[1],
                100 * shares[2], 100 * cfg.region_shares[0], 100 * cfg.region_shares[1], 100 * cfg.region_shares[2]);
  out << buf;
  std::size_t fixes = 0, nlos = 0, static_samples = 0;
  for (const auto& e : d.gnss) fixes += e.has_fix ? 1 : 0;
  for (const auto& r : d.uwb) nlos += r.nlos ? 1 : 0;
  for (const auto& t : d.truth) static_samples += t.is_static ? 1 : 0;
  std::snprintf(buf, sizeof buf, "  sensors: %zu IMU samples, %zu GNSS epochs (%zu fixes), %zu satellite observations, %zu UWB ranges (%.1f %% NLOS) from %zu anchors, %zu speed, %zu magnetometer\n",
                d.imu.size(), d.gnss.size(), fixes, d.sats.size(), d.uwb.size(), 100.0 * static_cast<double>(nlos) / std::max<double>(1.0, static_cast<double>(d.uwb.size())),
                d.world().anchors.size(), d.speed.size(), d.mag.size());
  out << buf;
  std::array<double, 3> sats{}, n{};
  for (const auto& e : d.gnss) {
    sats[static_cast<std::size_t>(e.region)] += e.num_sats;
    n[static_cast<std::size_t>(e.region)] += 1.0;
  }
  std::snprintf(buf, sizeof buf, "  mean tracked satellites outdoor/transition/indoor: %.1f/%.1f/%.1f; static: %.1f s\n",
                sats[0] / std::max(1.0, n[0]), sats[1] / std::max(1.0, n[1]), sats[2] / std::max(1.0, n[2]),
                static_cast<double>(static_samples) / d.config.imu.rate_hz);
  out << buf;
  j["seed"] = static_cast<double>(d.config.seed);
  j["duration_s"] = d.duration();
  j["length_m"] = d.route.length();
  Json s;
  for (int r = 0; r < 3; ++r) s[sim::region_name(static_cast<sim::Region>(r))] = shares[static_cast<std::size_t>(r)];
  j["region_shares"] = std::move(s);
  Json c;
  c["imu"] = static_cast<double>(d.imu.size());
  c["gnss_epochs"] = static_cast<double>(d.gnss.size());
  c["gnss_fixes"] = static_cast<double>(fixes);
  c["sat_observations"] = static_cast<double>(d.sats.size());
  c["uwb_ranges"] = static_cast<double>(d.uwb.size());
  c["uwb_nlos"] = static_cast<double>(nlos);
  c["speed"] = static_cast<double>(d.speed.size());
  c["mag"] = static_cast<double>(d.mag.size());
  j["counts"] = std::move(c);
  Json ms;
  for (int r = 0; r < 3; ++r)
    ms[sim::region_name(static_cast<sim::Region>(r))] = sats[static_cast<std::size_t>(r)] / std::max(1.0, n[static_cast<std::size_t>(r)]);
  j["mean_sats"] = std::move(ms);
}

/// The receiver's fixes scored like any pipeline; paper A's GNSS-alone row for reference.
void gnss_baseline(const sim::Drive& d, Json& j, std::ostream& out, Plotter* plotter) {
  std::vector<eval::TimedPosition> fixes;
  for (const auto& e : d.gnss)
    if (e.has_fix) fixes.push_back({e.t, e.position});
  const auto aligned = eval::align_to_truth(fixes, d.truth);
  const auto overall = eval::position_error_stats(aligned.errors);
  const auto by_region = eval::position_error_stats_by_label(aligned.errors, aligned.region, sim::kRegionCount);
  out << "GNSS fixes alone (no fix indoors; paper A's GNSS-alone mean error outdoor/transition: 1.94/1.71 m):\n";
  print_region_table(out, by_region, overall);
  j["overall"] = stats_json(overall);
  for (std::size_t r = 0; r < by_region.size(); ++r) j[sim::region_name(static_cast<sim::Region>(r))] = stats_json(by_region[r]);
  if (!plotter) return;
  Plotter::Series truth{"truth", {}, true}, gnss{"GNSS fixes", {}, false};
  for (std::size_t k = 0; k < d.truth.size(); k += 10) truth.points.emplace_back(d.truth[k].position.head<2>());
  for (const auto& f : fixes) gnss.points.emplace_back(f.position.head<2>());
  Plotter::Series anchors{"UWB anchors", {}, false};
  for (const auto& a : d.world().anchors) anchors.points.emplace_back(a.position.head<2>());
  plotter->trajectory("drive_trajectory", "Simulated drive: truth, GNSS fixes, UWB anchors", {truth, gnss, anchors});
  std::vector<std::pair<std::string, std::vector<double>>> cdf(2);
  cdf[0].first = "GNSS outdoor";
  cdf[1].first = "GNSS transition";
  for (std::size_t i = 0; i < aligned.errors.size(); ++i)
    if (aligned.region[i] < 2) cdf[static_cast<std::size_t>(aligned.region[i])].second.push_back(aligned.errors[i].head<2>().norm());
  plotter->error_cdf("gnss_error_cdf", "GNSS horizontal error CDF by region", cdf);
}

int demo_command(Args args, std::ostream& out, std::ostream& err) {
  CLI::App app = make_app("demo", "Simulates the drive and runs every built demo section against the papers' tables.");
  DemoContext ctx;
  ScenarioOptions scenario_options;
  std::string json_path, plot_dir;
  app.add_option("--seed", ctx.seed, "seed of the simulated drive (training and validation drives follow from it)")
      ->check(kNonNegativeInteger);
  add_scenario_options(app, scenario_options);
  app.add_option("--json", json_path, "write every number of the tables as JSON (docs/formats.md)");
  app.add_option("--plot", plot_dir, "write the sections' plots (PNG, gnuplot) into this directory");
  if (const auto rc = parse_options(app, args, out, err)) return *rc;
  const auto t0 = std::chrono::steady_clock::now();
  const std::string scenario = scenario_label(scenario_options);
  std::optional<sim::DriveConfig> cfg = scenario_config(scenario_options, "demo", err);
  if (!cfg) return 2;
  cfg->seed = ctx.seed;
  const sim::Drive drive = sim::simulate_drive(*cfg);
  ctx.drive = &drive;
  std::unique_ptr<Plotter> plotter;
  if (!plot_dir.empty()) {
    plotter = std::make_unique<Plotter>(plot_dir, err);
    if (plotter->available()) ctx.plotter = plotter.get();
  }

  Json doc;
  doc["seed"] = static_cast<double>(ctx.seed);
  doc["scenario"] = scenario;
  drive_summary(drive, doc["drive"], out);
  gnss_baseline(drive, doc["gnss_alone"], out, ctx.plotter);

  // The papers' sections first, in their order; any other registered section after them.
  std::vector<const DemoSection*> extra;
  for (const auto& s : demo_sections()) {
    bool known = false;
    for (const auto& slot : kSectionOrder) known = known || slot.key == s.key;
    if (!known) extra.push_back(&s);
  }
  Progress progress(err, "ctxfuse demo", static_cast<double>(kSectionOrder.size() + extra.size()));
  std::size_t done = 0;
  auto run_section = [&](const DemoSection& s) {
    out << '\n' << s.title << '\n';
    s.run(ctx, doc[s.key], out);
    progress.update(static_cast<double>(++done));
  };
  for (const auto& slot : kSectionOrder) {
    const DemoSection* found = nullptr;
    for (const auto& s : demo_sections())
      if (s.key == slot.key) found = &s;
    if (found) {
      progress.finish();
      run_section(*found);
    } else {
      out << '\n' << slot.title << ": not built\n";
      ++done;
    }
  }
  for (const auto* s : extra) {
    progress.finish();
    run_section(*s);
  }
  progress.finish();
  if (plotter && plotter->available()) {
    out << "\nplots in " << plotter->dir().string() << ":";
    for (const auto& p : plotter->written()) out << ' ' << p.filename().string();
    out << '\n';
  }
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  doc["elapsed_s"] = elapsed;
  if (!json_path.empty() && !write_json_file(doc, json_path, "demo", err)) return 1;
  return 0;
}

const RegisterCommand reg_demo{{"demo", "simulate the default drive and run every demo section", demo_command}};

}  // namespace
}  // namespace ctxfuse::cli

// The simulated UWB site (sim/uwb_site.hpp) and what the pipeline takes from a recording
// (pipelines/nlos_uwb/recording.hpp):
// - the simulator's ranges have the configured bias, noise, averaging, rate and NLOS excess;
// - describe_recording finds the report period and tells raw reports from 3-sample means on
//   the static start, and says when the static start is too short to tell;
// - the indoor case of issue 30's "must show", written in the Hanyang layout and read back:
//   8 anchors around a 20 m x 20 m yard, 100 Hz raw ranges, per-anchor biases 0.1-0.3 m, a
//   walk: the self-calibrating EKF (consistency check only, no labelled data) is below a
//   per-epoch least squares of the same ranges.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "ctxfuse/instances/nlos_uwb.hpp"
#include "ctxfuse/pipelines/nlos_uwb/recording.hpp"
#include "ctxfuse/sim/uwb_site.hpp"

namespace nu = ctxfuse::pipelines::nlos_uwb;
namespace sim = ctxfuse::sim;

namespace {

/// 8 anchors around the 20 m x 20 m yard (corners and mid-sides), heights alternating 0.5 and
/// 2.0 m, biases 0.10 ... 0.30 m, all at `rate_hz`, answering 0.5 ms apart.
std::vector<sim::SiteAnchor> yard_anchors(double rate_hz) {
  const double xy[8][2] = {{-1, -1}, {10, -1}, {21, -1}, {21, 10}, {21, 21}, {10, 21}, {-1, 21}, {-1, 10}};
  std::vector<sim::SiteAnchor> out;
  for (int k = 0; k < 8; ++k)
    out.push_back({k + 1, {xy[k][0], xy[k][1], k % 2 ? 2.0 : 0.5}, rate_hz, 0.0005 * k, 0.10 + 0.2 * k / 7.0});
  return out;
}

}  // namespace

TEST(UwbSite, RangesHaveTheConfiguredStatistics) {
  // At rest 5 m from one anchor for 20 s.
  const std::vector<sim::PositionSample> path{{0.0, {5, 0, 1}}, {20.0, {5, 0, 1}}};
  sim::UwbSiteConfig c;
  c.anchors = {{7, {0, 0, 1}, 50.0, 0.0, 0.2}};
  c.noise_sigma_m = 0.1;
  const auto raw = sim::simulate_uwb_site(path, c);
  ASSERT_EQ(raw.size(), 1001u);  // slots 0, 0.02, ..., 20.0
  double mean = 0.0, sq = 0.0;
  for (const auto& r : raw) mean += (r.range_m - 5.0) / raw.size();
  for (const auto& r : raw) sq += (r.range_m - 5.0 - mean) * (r.range_m - 5.0 - mean) / (raw.size() - 1);
  EXPECT_NEAR(mean, 0.2, 4.0 * 0.1 / std::sqrt(1001.0));  // 4 standard errors
  EXPECT_NEAR(std::sqrt(sq), 0.1, 0.01);                   // 4 standard errors of a std (2.2 % each)
  EXPECT_DOUBLE_EQ(raw[10].t, 0.2);
  // The mean of 3: sigma / sqrt(3); the same seed, the same raw draws.
  c.average_samples = 3;
  const auto avg = sim::simulate_uwb_site(path, c);
  sq = 0.0;
  for (std::size_t i = 2; i < avg.size(); ++i) {
    EXPECT_NEAR(avg[i].range_m, (raw[i].range_m + raw[i - 1].range_m + raw[i - 2].range_m) / 3.0, 1e-12);
    sq += (avg[i].range_m - 5.2) * (avg[i].range_m - 5.2) / (avg.size() - 2);
  }
  EXPECT_NEAR(std::sqrt(sq), 0.1 / std::sqrt(3.0), 0.1 / std::sqrt(3.0) * 0.1);
  // NLOS excess: every range NLOS, exponential mean 0.5 m; the first path 6 dB lower.
  c.average_samples = 1;
  c.nlos = {1.0, 0.5, 6.0};
  const auto nlos = sim::simulate_uwb_site(path, c);
  mean = 0.0;
  for (const auto& r : nlos) mean += (r.range_m - 5.2) / nlos.size();
  EXPECT_NEAR(mean, 0.5, 4.0 * std::sqrt(0.25 + 0.01) / std::sqrt(1001.0));
  EXPECT_DOUBLE_EQ(nlos[0].rssi_dbm - nlos[0].rssi_first_path_dbm, 7.0);
  // Bad configurations are refused.
  c.anchors[0].rate_hz = 0.0;
  EXPECT_THROW(sim::simulate_uwb_site(path, c), std::invalid_argument);
  c.anchors = {{1, {0, 0, 0}, 10.0, 0.0, 0.0}, {1, {1, 0, 0}, 10.0, 0.0, 0.0}};
  EXPECT_THROW(sim::simulate_uwb_site(path, c), std::invalid_argument);
}

TEST(UwbSite, RecordingFactsFindPeriodAndAveraging) {
  sim::WalkConfig w;
  w.walk_s = 30.0;
  const auto path = sim::pedestrian_walk(w);
  sim::UwbSiteConfig c;
  c.anchors = yard_anchors(100.0);
  c.rate_jitter_s = 0.0003;
  for (int n : {1, 3}) {
    c.average_samples = n;
    const auto ranges = sim::simulate_uwb_site(path, c);
    const auto f = nu::describe_recording(ranges);
    ASSERT_EQ(f.anchors.size(), 8u);
    EXPECT_NEAR(f.range_period_s, 0.01, 1e-4);
    EXPECT_TRUE(f.averaging_detected) << f.averaging_note;
    EXPECT_EQ(f.range_average_samples, n) << f.averaging_note;
    // The walk starts at 10 s; the static start found ends before it, within a second of the
    // 2 s margin (the ranges leave their band some time after the walk starts).
    EXPECT_LT(f.static_start_s, 10.0 - 2.0 + 1.0);
    EXPECT_GT(f.static_start_s, 4.0);
    std::printf("average %d: static start %.2f s, autocorrelation lags 1-4 %+.2f %+.2f %+.2f %+.2f\n", n, f.static_start_s,
                f.autocorrelation[0], f.autocorrelation[1], f.autocorrelation[2], f.autocorrelation[3]);
    std::string problem;
    const nu::Settings s = nu::settings_for_recording(f, nu::Settings{}, 0, problem);
    EXPECT_EQ(problem, "");
    EXPECT_EQ(s.range_average_samples, n);
    EXPECT_NEAR(s.epoch_window_s, 0.005, 1e-4);
  }
  // No static start: not detected, raw assumed, and said.
  w.static_s = 0.0;
  c.average_samples = 3;
  const auto moving = nu::describe_recording(sim::simulate_uwb_site(sim::pedestrian_walk(w), c));
  EXPECT_FALSE(moving.averaging_detected);
  EXPECT_EQ(moving.range_average_samples, 1);
  EXPECT_NE(moving.averaging_note.find("raw assumed"), std::string::npos) << moving.averaging_note;
  // Two anchors are too few.
  c.anchors.resize(2);
  std::string problem;
  nu::settings_for_recording(nu::describe_recording(sim::simulate_uwb_site(path, c)), nu::Settings{}, 0, problem);
  EXPECT_NE(problem.find("2 anchors"), std::string::npos) << problem;
}

// The tag's height from the static start: with two anchors overhead (on a ceiling) the fit
// observes it (vertical sigma under 0.1 m) and the settings take it; the yard's eight anchors
// alone (0.5 and 2 m high, 11-15 m away, 0.1-0.3 m biases) leave it to the default, which the
// source says, and an option overrides both.
TEST(UwbSite, TagHeightFromTheStaticStartWhenTheAnchorsObserveIt) {
  sim::WalkConfig w;
  w.walk_s = 20.0;
  w.tag_height_m = 1.4;
  const auto path = sim::pedestrian_walk(w);  // at rest at (10, 10) for 10 s
  sim::UwbSiteConfig c;
  c.anchors = yard_anchors(10.0);
  for (auto& a : c.anchors) a.bias_m = 0.0;
  c.anchors.push_back({9, {9.5, 10.0, 4.0}, 10.0, 0.0, 0.0});
  c.anchors.push_back({10, {10.5, 10.0, 4.0}, 10.0, 0.0, 0.0});
  const auto f = nu::describe_recording(sim::simulate_uwb_site(path, c));
  ASSERT_TRUE(std::isfinite(f.tag_height_m)) << f.tag_height_note;
  const nu::Settings def;
  const double sigma = f.tag_height_vdop * def.range_sigma_m;
  EXPECT_LT(sigma, def.tag_height_max_sigma_m);
  // The median of ~70 ranges an anchor (10 Hz, 7 s) has a sigma near 0.1 x 1.25 / sqrt(70).
  EXPECT_NEAR(f.tag_height_m, 1.4, 4.0 * f.tag_height_vdop * 0.1 * 1.25 / std::sqrt(70.0)) << f.tag_height_vdop;
  std::string problem, source;
  nu::Settings s = nu::settings_for_recording(f, def, 0, problem, std::nan(""), &source);
  EXPECT_EQ(problem, "");
  EXPECT_EQ(s.tag_height_m, f.tag_height_m);
  EXPECT_EQ(source.rfind("static start", 0), 0u) << source;
  s = nu::settings_for_recording(f, def, 0, problem, 0.8, &source);
  EXPECT_EQ(s.tag_height_m, 0.8);
  EXPECT_EQ(source, "option");
  // The yard alone, biased as in the other tests: the fit is too loose to take.
  c.anchors = yard_anchors(10.0);
  const auto yard = nu::describe_recording(sim::simulate_uwb_site(path, c));
  s = nu::settings_for_recording(yard, def, 0, problem, std::nan(""), &source);
  EXPECT_GT(yard.tag_height_vdop * def.range_sigma_m, def.tag_height_max_sigma_m);
  EXPECT_EQ(s.tag_height_m, def.tag_height_m);
  EXPECT_EQ(source.rfind("default", 0), 0u) << source;
}

// Rates of 1 to 100 Hz in one recording: each anchor's period found, the epoch window from the
// fastest, and the self-calibrating EKF still tracks the walk.
TEST(UwbSite, MixedRatesOneToHundredHertz) {
  sim::WalkConfig w;
  w.walk_s = 60.0;
  const auto path = sim::pedestrian_walk(w);
  sim::UwbSiteConfig c;
  c.anchors = yard_anchors(100.0);
  const double rates[8] = {1.0, 100.0, 10.0, 50.0, 1.0, 100.0, 10.0, 50.0};
  for (std::size_t k = 0; k < 8; ++k) c.anchors[k].rate_hz = rates[k];
  c.rate_jitter_s = 0.0003;
  c.seed = 3;
  const auto ranges = sim::simulate_uwb_site(path, c);
  const auto f = nu::describe_recording(ranges);
  ASSERT_EQ(f.anchors.size(), 8u);
  for (std::size_t k = 0; k < 8; ++k) EXPECT_NEAR(f.anchors[k].median_interval_s, 1.0 / rates[k], 2e-4) << k;
  std::string problem;
  const nu::Settings s = nu::settings_for_recording(f, nu::Settings{}, 0, problem);
  ASSERT_EQ(problem, "");
  EXPECT_NEAR(s.epoch_window_s, 0.005, 1e-4);
  // The 1 Hz anchors give 8 differences on the static start, too few: left out; the others
  // show raw reports.
  EXPECT_TRUE(f.averaging_detected) << f.averaging_note;
  EXPECT_EQ(s.range_average_samples, 1);
  const std::string_view names[] = {"calibrated_ekf_gate_per_range", "least_squares"};
  auto variants = ctxfuse::studies::run_nlos_uwb_variants(ranges, nu::NlosClassifier(s), s, names);
  ctxfuse::studies::score_nlos_uwb_variants(variants, sim::hanyang_reference(path, w.tag_height_m), ctxfuse::studies::choose_protocol("none", {}));
  std::printf("mixed 1-100 Hz: calibrated EKF %.4f m, least squares %.4f m\n", variants[0].rmse.rmse_2d, variants[1].rmse.rmse_2d);
  EXPECT_LT(variants[0].rmse.rmse_2d, 0.5 * variants[1].rmse.rmse_2d);
}

TEST(UwbSite, IndoorYardCalibratedEkfBeatsLeastSquares) {
  sim::WalkConfig w;
  w.walk_s = 120.0;
  const auto path = sim::pedestrian_walk(w);
  sim::UwbSiteConfig c;
  c.anchors = yard_anchors(100.0);
  c.rate_jitter_s = 0.0003;
  c.seed = 7;
  const auto dir = std::filesystem::temp_directory_path() / ("ctxfuse_uwb_yard_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  ctxfuse::io::write_hanyang_case(dir, sim::simulate_uwb_site(path, c), sim::hanyang_reference(path, w.tag_height_m));
  // Read back as `run uwb` reads a recording.
  const auto ranges = ctxfuse::io::read_hanyang_uwb(dir).uwb_ranges();
  const auto ref = ctxfuse::io::read_hanyang_reference(dir);
  std::filesystem::remove_all(dir);
  const auto facts = nu::describe_recording(ranges);
  std::string problem;
  const nu::Settings s = nu::settings_for_recording(facts, nu::Settings{}, 0, problem);
  ASSERT_EQ(problem, "");
  EXPECT_EQ(s.range_average_samples, 1);
  const nu::NlosClassifier classifier(s);  // no labelled data: the consistency check alone
  const std::string_view names[] = {"calibrated_ekf_gate_per_range", "least_squares"};
  auto variants = ctxfuse::studies::run_nlos_uwb_variants(ranges, classifier, s, names);
  const auto protocol = ctxfuse::studies::choose_protocol("auto", ref);  // a yard: neither Hanyang span
  EXPECT_EQ(protocol.name, "whole_run");
  ctxfuse::studies::score_nlos_uwb_variants(variants, ref, protocol);
  const double ekf = variants[0].rmse.rmse_2d, ls = variants[1].rmse.rmse_2d;
  std::printf("indoor yard, 8 anchors at 100 Hz, biases 0.1-0.3 m: calibrated EKF %.4f m (%zu scored), least squares %.4f m (%zu)\n",
              ekf, variants[0].rmse.scored, ls, variants[1].rmse.scored);
  EXPECT_GT(variants[0].rmse.scored, 10000u);
  EXPECT_GT(variants[1].rmse.scored, 10000u);
  EXPECT_LT(ekf, 0.5 * ls);
}

// `ctxfuse run uwb` end to end on one Hanyang case (real data; skipped without it): the
// trajectory CSV (time_ns,x,y,z, one row per estimate) scored again here with the authors'
// protocol gives the JSON's figure; the JSON names a leave-one-out split; usage errors; --plot
// writes its three plots, whose data agree with the JSON. More in run_uwb_any_test.cpp (runs
// without reference or siblings, spans, `ctxfuse score`, a simulated case).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli/plot_data.hpp"
#include "ctxfuse/studies/hanyang_protocol.hpp"
#include "support/data_dir.hpp"
#include "support/run_cli.hpp"

namespace fs = std::filesystem;

// Named, not anonymous: the area's sources share one unity build (tests/CMakeLists.txt).
namespace run_uwb_cli {

ctxfuse::test::CliRun run(const std::string& args) { return ctxfuse::test::run_cli(args, ctxfuse::test::Stderr::separate); }

TEST(CliRunUwb, TrajectoryAndMetricsOfOneCase) {
  CTXFUSE_REQUIRE_DATA(dir, "uwb-outdoor-hanyang/Dynamic_measurements/NLOS/Trajectory_A/Case_1");
  const fs::path tmp = ctxfuse::test::scratch_dir("run_uwb");
  // The fixed-lag output: its rows carry the times of the smoothed states, 0.9 s behind.
  const auto r = run("run uwb --data \"" + dir.string() + "\" --estimator calibrated-lag --out \"" + (tmp / "traj.csv").string() +
                     "\" --json \"" + (tmp / "metrics.json").string() + "\"");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("calibrated_ekf_gate_per_range_lag"), std::string::npos) << r.out;

  std::ifstream js(tmp / "metrics.json");
  const nlohmann::json doc = nlohmann::json::parse(js);
  EXPECT_EQ(doc.at("trajectory_variant"), "calibrated_ekf_gate_per_range_lag");
  ASSERT_EQ(doc.at("training_cases").size(), 3u);
  for (const auto& c : doc.at("training_cases")) EXPECT_NE(fs::weakly_canonical(c.get<std::string>()), fs::weakly_canonical(dir));
  const double authors_ls = doc.at("authors_rmse_2d_m").at("LS"), authors_eskf = doc.at("authors_rmse_2d_m").at("ESKF");
  const double ours = doc.at("rmse_2d_m").at("calibrated_ekf_gate_per_range_lag");
  EXPECT_LT(ours, std::min(authors_ls, authors_eskf));
  EXPECT_LE(ours, 0.6);  // issue 16's target on this case
  EXPECT_LT(doc.at("rmse_2d_m").at("calibrated_ekf_gate_per_range").get<double>(), doc.at("rmse_2d_m").at("ekf_gate_per_range").get<double>());
  EXPECT_GT(doc.at("identification").at("ds").at("accuracy").get<double>(), 0.5);

  // The CSV: header, one row per estimate, and the same score when read back.
  std::ifstream csv(tmp / "traj.csv");
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  EXPECT_EQ(line, "time_ns,x,y,z");
  std::vector<ctxfuse::studies::TimedPoint2> est;
  while (std::getline(csv, line)) {
    std::stringstream ss(line);
    std::string f[4];
    for (auto& s : f) std::getline(ss, s, ',');
    const std::int64_t t_ns = std::stoll(f[0]);
    est.push_back({static_cast<double>(t_ns / 1'000'000'000) + static_cast<double>(t_ns % 1'000'000'000) * 1e-9,
                   {std::stod(f[1]), std::stod(f[2])}});
    EXPECT_DOUBLE_EQ(std::stod(f[3]), 1.0);  // the tag's fixed height
  }
  EXPECT_EQ(static_cast<double>(est.size()), doc.at("estimates").get<double>());
  const auto ref = ctxfuse::io::read_hanyang_reference(dir);
  const auto again = ctxfuse::studies::hanyang_rmse_2d(est, ref, ctxfuse::studies::trajectory_a_span());
  // Times written to the ns and positions to 17 digits: the same figure to rounding.
  EXPECT_NEAR(again.rmse_2d, ours, 1e-6);
  fs::remove_all(tmp);
}

TEST(CliRunUwb, UsageAndInputErrors) {
  const fs::path empty = fs::temp_directory_path() / ("ctxfuse_run_uwb_empty_" + std::to_string(::getpid()));
  fs::create_directories(empty);
  const auto bad_policy = run("run uwb --data \"" + empty.string() + "\" --policy sometimes");
  EXPECT_EQ(bad_policy.code, 2);
  EXPECT_NE(bad_policy.err.find("--policy"), std::string::npos) << bad_policy.err;
  const auto bad_estimator = run("run uwb --data \"" + empty.string() + "\" --estimator kalman");
  EXPECT_EQ(bad_estimator.code, 2);
  EXPECT_NE(bad_estimator.err.find("--estimator"), std::string::npos) << bad_estimator.err;
  const auto no_ranges = run("run uwb --data \"" + empty.string() + "\"");
  EXPECT_EQ(no_ranges.code, 1);
  EXPECT_NE(no_ranges.err.find("A<id>.csv"), std::string::npos) << no_ranges.err;
  fs::remove_all(empty);
}

TEST(CliRunUwb, PlotsAgreeWithTheMetrics) {
  CTXFUSE_REQUIRE_DATA(dir, "uwb-outdoor-hanyang/Dynamic_measurements/NLOS/Trajectory_A/Case_1");
  CTXFUSE_REQUIRE_GNUPLOT();
  namespace t = ctxfuse::test;
  const fs::path tmp = t::scratch_dir("run_uwb_plot");
  const fs::path plots = tmp / "plots";
  // The paper's epoch rule: it leaves whole epochs out, which the plots mark.
  const auto r = run("run uwb --data \"" + dir.string() + "\" --policy paper --json \"" + (tmp / "m.json").string() + "\" --plot \"" +
                     plots.string() + "\"");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("plots in " + plots.string() + ": uwb_trajectory.png uwb_error_time.png uwb_error_cdf.png"), std::string::npos)
      << r.out;
  std::ifstream js(tmp / "m.json");
  const nlohmann::json doc = nlohmann::json::parse(js);
  const std::string v = doc.at("trajectory_variant");
  ASSERT_EQ(v, "calibrated_ekf_gate_paper_rule");  // the default estimator

  // Plan view: every estimate, the left-out epochs on their own; one point per anchor file.
  const auto traj = t::expect_plot(plots, "uwb_trajectory");
  const auto& left = traj.at(v + ", left-out epochs");
  const auto& attached = traj.at(v + ", epochs with ranges attached");
  EXPECT_EQ(static_cast<double>(left.size()), doc.at("epochs_left_out").at(v).get<double>());
  EXPECT_GT(left.size(), 0u);
  EXPECT_EQ(static_cast<double>(left.size() + attached.size()), doc.at("estimates").get<double>());
  std::size_t anchor_files = 0;
  for (const auto& f : fs::directory_iterator(dir)) {
    const std::string name = f.path().filename().string();
    anchor_files += name.size() > 5 && name[0] == 'A' && name.ends_with(".csv") && std::isdigit(static_cast<unsigned char>(name[1]));
  }
  EXPECT_EQ(traj.at("UWB anchors").size(), anchor_files);
  EXPECT_GT(traj.at("reference").size(), 100u);

  // Error over time: the protocol's errors, whose RMS is the JSON's; the marked left-out
  // epochs are points of that curve.
  const auto err = t::expect_plot(plots, "uwb_error_time");
  const auto& e = err.at(v + " 2-D error");
  const double rmse = doc.at("rmse_2d_m").at(v);
  EXPECT_NEAR(t::rms_y(e), rmse, t::six_digits(rmse));
  ASSERT_TRUE(err.count("left-out epochs"));
  const auto& marked = err.at("left-out epochs");
  EXPECT_GT(marked.size(), 0u);
  EXPECT_LE(marked.size(), left.size());
  for (const auto& p : marked) EXPECT_NE(std::find(e.begin(), e.end(), p), e.end()) << p.first;

  // CDF: the same errors sorted; the authors' ESKF, scored here from their ESKF.csv, gives
  // the figure of their RMSD_results.txt (4 decimals there).
  const auto cdf = t::expect_plot(plots, "uwb_error_cdf");
  const auto& c = cdf.at(v);
  ASSERT_EQ(c.size(), e.size());
  EXPECT_TRUE(std::is_sorted(c.begin(), c.end()));
  EXPECT_DOUBLE_EQ(c.back().second, 1.0);
  double sum = 0.0;
  for (const auto& p : c) sum += p.first * p.first;
  EXPECT_NEAR(std::sqrt(sum / static_cast<double>(c.size())), rmse, t::six_digits(rmse));
  ASSERT_TRUE(cdf.count("authors' ESKF"));
  double eskf = 0.0;
  for (const auto& p : cdf.at("authors' ESKF")) eskf += p.first * p.first;
  eskf = std::sqrt(eskf / static_cast<double>(cdf.at("authors' ESKF").size()));
  EXPECT_NEAR(eskf, doc.at("authors_rmse_2d_m").at("ESKF").get<double>(), 1e-3);
  fs::remove_all(tmp);
}

}  // namespace run_uwb_cli

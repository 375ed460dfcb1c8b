// `ctxfuse run uwb` end to end on one Hanyang case (real data; skipped without it): the
// trajectory CSV (time_ns,x,y,z, one row per estimate) scored again here with the authors'
// protocol gives the JSON's figure; the JSON names a leave-one-out split; usage errors.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "ctxfuse/eval/hanyang_protocol.hpp"
#include "support/data_dir.hpp"
#include "support/run_cli.hpp"

namespace fs = std::filesystem;

namespace {

ctxfuse::test::CliRun run(const std::string& args) { return ctxfuse::test::run_cli(args, ctxfuse::test::Stderr::separate); }

}  // namespace

TEST(CliRunUwb, TrajectoryAndMetricsOfOneCase) {
  CTXFUSE_REQUIRE_DATA(dir, "uwb-outdoor-hanyang/Dynamic_measurements/NLOS/Trajectory_A/Case_1");
  const fs::path tmp = fs::temp_directory_path() / ("ctxfuse_run_uwb_" + std::to_string(::getpid()));
  fs::create_directories(tmp);
  const auto r = run("run uwb --data \"" + dir.string() + "\" --out \"" + (tmp / "traj.csv").string() + "\" --json \"" +
                     (tmp / "metrics.json").string() + "\"");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("ekf_gate_per_range"), std::string::npos) << r.out;

  std::ifstream js(tmp / "metrics.json");
  const nlohmann::json doc = nlohmann::json::parse(js);
  EXPECT_EQ(doc.at("trajectory_variant"), "ekf_gate_per_range");
  ASSERT_EQ(doc.at("training_cases").size(), 3u);
  for (const auto& c : doc.at("training_cases")) EXPECT_NE(fs::weakly_canonical(c.get<std::string>()), fs::weakly_canonical(dir));
  const double authors_ls = doc.at("authors_rmse_2d_m").at("LS"), authors_eskf = doc.at("authors_rmse_2d_m").at("ESKF");
  const double ours = doc.at("rmse_2d_m").at("ekf_gate_per_range");
  EXPECT_LT(ours, std::min(authors_ls, authors_eskf));
  EXPECT_GT(doc.at("identification").at("ds").at("accuracy").get<double>(), 0.5);

  // The CSV: header, one row per estimate, and the same score when read back.
  std::ifstream csv(tmp / "traj.csv");
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  EXPECT_EQ(line, "time_ns,x,y,z");
  std::vector<ctxfuse::eval::TimedPoint2> est;
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
  const auto again = ctxfuse::eval::hanyang_rmse_2d(est, ref, ctxfuse::eval::trajectory_a_span());
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
  const auto no_ranges = run("run uwb --data \"" + empty.string() + "\"");
  EXPECT_EQ(no_ranges.code, 1);
  EXPECT_NE(no_ranges.err.find("A<id>.csv"), std::string::npos) << no_ranges.err;
  fs::remove_all(empty);
}

// `ctxfuse run uwb` on any folder of A<id>.csv files, and `ctxfuse score`:
// - every Hanyang dynamic case with its reference (scored, trajectory A's span found by auto)
//   and as a lone folder of its A*.csv files only (no reference, no siblings: consistency check
//   alone, nothing scored); the report averaging and period found on each;
// - an SVM saved by a training run (--save-nlos-model) and given to a lone folder
//   (--nlos-model) gives the training run's trajectory byte for byte;
// - a span the reference does not fit is a warning; the trajectory is still written, exit 0;
// - `ctxfuse score` reproduces the authors' RMSD_results.txt from their LS.csv, and a small
//   case computed by hand with either span form and over the whole run;
// - a simulated indoor case in the Hanyang layout (8 anchors, 100 Hz raw, biases 0.1-0.3 m):
//   the default trajectory below least squares.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "ctxfuse/studies/hanyang_protocol.hpp"
#include "ctxfuse/sim/uwb_site.hpp"
#include "support/data_dir.hpp"
#include "support/run_cli.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

// Named, not anonymous: the area's sources share one unity build (tests/CMakeLists.txt).
namespace run_uwb_any_cli {

ctxfuse::test::CliRun run(const std::string& args) { return ctxfuse::test::run_cli(args, ctxfuse::test::Stderr::separate); }

std::string q(const fs::path& p) { return "\"" + p.string() + "\""; }

json read_json(const fs::path& p) {
  std::ifstream is(p);
  return json::parse(is);
}

std::string read_text(const fs::path& p) {
  std::ifstream is(p);
  std::stringstream ss;
  ss << is.rdbuf();
  return ss.str();
}

std::size_t lines(const fs::path& p) {
  const std::string t = read_text(p);
  return static_cast<std::size_t>(std::count(t.begin(), t.end(), '\n'));
}

/// Copies only the A<id>.csv files of `from` into `to`.
void copy_ranges(const fs::path& from, const fs::path& to) {
  fs::create_directories(to);
  for (const auto& f : fs::directory_iterator(from)) {
    const std::string n = f.path().filename().string();
    if (n.size() > 5 && n[0] == 'A' && n.ends_with(".csv")) fs::copy_file(f.path(), to / n);
  }
}

constexpr const char* kCases[] = {"LOS/Trajectory_A/Case_1", "LOS/Trajectory_A/Case_2", "NLOS/Trajectory_A/Case_1",
                                  "NLOS/Trajectory_A/Case_2"};

TEST(CliRunUwbAny, EveryCaseWithAndWithoutItsReference) {
  CTXFUSE_REQUIRE_DATA(root, "uwb-outdoor-hanyang/Dynamic_measurements");
  const fs::path tmp = ctxfuse::test::scratch_dir("run_uwb_any");
  for (const char* c : kCases) {
    const fs::path dir = root / c;
    const fs::path lone = tmp / "lone";
    fs::remove_all(lone);
    copy_ranges(dir, lone);
    const auto with = run("run uwb --data " + q(dir) + " --out " + q(tmp / "with.csv") + " --json " + q(tmp / "with.json") +
                          " --save-nlos-model " + q(tmp / "svm.txt"));
    ASSERT_EQ(with.code, 0) << c << with.err;
    EXPECT_EQ(with.err, "") << c;  // trajectory A's span fits: no warning
    const json w = read_json(tmp / "with.json");
    EXPECT_EQ(w.at("nlos_classifier"), "svm-siblings") << c;
    EXPECT_EQ(w.at("training_cases").size(), 3u) << c;
    EXPECT_EQ(w.at("scoring").at("protocol"), "trajectory_a") << c;
    EXPECT_EQ(w.at("rmse_2d_m").size(), 17u) << c;
    // The Hanyang firmware's 3-sample mean and 10 Hz period, found on the recording itself.
    EXPECT_EQ(w.at("settings").at("range_average_samples"), 3) << c << w.at("recording").at("range_average_note");
    EXPECT_NEAR(w.at("settings").at("range_period_s").get<double>(), 0.1, 0.002) << c;
    EXPECT_EQ(w.at("recording").at("anchors").size(), 4u);
    EXPECT_EQ(lines(tmp / "with.csv"), w.at("estimates").get<std::size_t>() + 1) << c;

    // The lone folder: nothing but ranges. Consistency check alone; nothing scored.
    const auto alone = run("run uwb --data " + q(lone) + " --out " + q(tmp / "alone.csv") + " --json " + q(tmp / "alone.json"));
    ASSERT_EQ(alone.code, 0) << c << alone.err;
    const json a = read_json(tmp / "alone.json");
    EXPECT_EQ(a.at("nlos_classifier"), "consistency-only") << c;
    EXPECT_FALSE(a.contains("rmse_2d_m")) << c;
    EXPECT_FALSE(a.contains("scoring")) << c;
    EXPECT_EQ(a.at("settings"), w.at("settings")) << c;
    EXPECT_GT(a.at("run").at("ranges_accepted").get<double>(), 0.8 * a.at("run").at("ranges").get<double>()) << c;
    EXPECT_EQ(lines(tmp / "alone.csv"), a.at("estimates").get<std::size_t>() + 1) << c;
    EXPECT_GT(a.at("estimates").get<double>(), 1500.0) << c;

    // The saved SVM on the lone folder: the training run's trajectory, byte for byte.
    const auto from_file = run("run uwb --data " + q(lone) + " --nlos-model " + q(tmp / "svm.txt") + " --out " + q(tmp / "file.csv") +
                               " --json " + q(tmp / "file.json"));
    ASSERT_EQ(from_file.code, 0) << c << from_file.err;
    EXPECT_EQ(read_json(tmp / "file.json").at("nlos_classifier"), "svm-file");
    EXPECT_EQ(read_text(tmp / "file.csv"), read_text(tmp / "with.csv")) << c;
    EXPECT_NE(read_text(tmp / "alone.csv"), read_text(tmp / "with.csv")) << c;  // the SVM changes the run
  }
  fs::remove_all(tmp);
}

TEST(CliRunUwbAny, SpansAndWarnings) {
  CTXFUSE_REQUIRE_DATA(dir, "uwb-outdoor-hanyang/Dynamic_measurements/NLOS/Trajectory_A/Case_1");
  const fs::path tmp = ctxfuse::test::scratch_dir("run_uwb_spans");
  const auto a = run("run uwb --data " + q(dir) + " --json " + q(tmp / "a.json"));
  ASSERT_EQ(a.code, 0) << a.err;
  // The same span written out as text: the same figures.
  const auto custom = run("run uwb --data " + q(dir) + " --span \"x>49.3,y>-5/x<=12,y>3.4\" --json " + q(tmp / "c.json"));
  ASSERT_EQ(custom.code, 0) << custom.err;
  EXPECT_EQ(read_json(tmp / "c.json").at("rmse_2d_m"), read_json(tmp / "a.json").at("rmse_2d_m"));
  EXPECT_EQ(read_json(tmp / "c.json").at("scoring").at("protocol"), "custom");
  // Trajectory B's span on trajectory A: the reference never passes B's end gate after its
  // start. A warning naming why, the whole run scored, the trajectory written, exit 0.
  const auto b = run("run uwb --data " + q(dir) + " --span b --out " + q(tmp / "b.csv") + " --json " + q(tmp / "b.json"));
  ASSERT_EQ(b.code, 0) << b.err;
  EXPECT_NE(b.err.find("warning: span b: the reference never"), std::string::npos) << b.err;
  const json jb = read_json(tmp / "b.json");
  EXPECT_EQ(jb.at("scoring").at("protocol"), "whole_run");
  EXPECT_GT(lines(tmp / "b.csv"), 1000u);
  // The whole run scores more estimates than the span.
  EXPECT_GT(jb.at("scoring").at("scored").get<double>(), read_json(tmp / "a.json").at("scoring").at("scored").get<double>());
  // An explicit reference elsewhere, and the averaging given by option.
  fs::copy_file(dir / "trajectory.csv", tmp / "ref.csv");
  const auto r = run("run uwb --data " + q(dir) + " --reference " + q(tmp / "ref.csv") + " --range-average 1 --json " + q(tmp / "r.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  const json jr = read_json(tmp / "r.json");
  EXPECT_EQ(jr.at("settings").at("range_average_samples"), 1);
  EXPECT_EQ(jr.at("settings").at("range_average_source"), "option");
  EXPECT_NE(jr.at("rmse_2d_m").at("calibrated_ekf_gate_per_range"), read_json(tmp / "a.json").at("rmse_2d_m").at("calibrated_ekf_gate_per_range"));
  // Usage errors.
  EXPECT_EQ(run("run uwb --data " + q(dir) + " --span c").code, 2);
  EXPECT_EQ(run("run uwb --data " + q(dir) + " --span \"x>1\"").code, 2);
  EXPECT_EQ(run("run uwb --data " + q(dir) + " --range-average 2.5").code, 2);
  EXPECT_EQ(run("run uwb --data " + q(dir) + " --range-average 0").code, 2);
  EXPECT_EQ(run("run uwb --data " + q(dir) + " --nlos-model " + q(tmp / "ref.csv") + " --train " + q(dir.parent_path() / "Case_2")).code, 2);
  // Nothing to save on a lone folder: an error, after the trajectory and the JSON are written.
  copy_ranges(dir, tmp / "lone");
  const auto nothing = run("run uwb --data " + q(tmp / "lone") + " --save-nlos-model " + q(tmp / "m.txt") + " --out " + q(tmp / "l.csv") +
                           " --json " + q(tmp / "l.json"));
  EXPECT_EQ(nothing.code, 1);
  EXPECT_NE(nothing.err.find("--save-nlos-model: this run has no SVM"), std::string::npos) << nothing.err;
  EXPECT_GT(lines(tmp / "l.csv"), 1000u);
  EXPECT_EQ(read_json(tmp / "l.json").at("nlos_classifier"), "consistency-only");
  EXPECT_FALSE(fs::exists(tmp / "m.txt"));
  // A model file that is not a model: a runtime error naming it.
  const auto bad_model = run("run uwb --data " + q(dir) + " --nlos-model " + q(tmp / "ref.csv"));
  EXPECT_EQ(bad_model.code, 1);
  EXPECT_NE(bad_model.err.find("ref.csv"), std::string::npos) << bad_model.err;
  fs::remove_all(tmp);
}

TEST(CliScore, AuthorsFiguresFromTheirFiles) {
  CTXFUSE_REQUIRE_DATA(dir, "uwb-outdoor-hanyang/Dynamic_measurements/NLOS/Trajectory_A/Case_1");
  const fs::path tmp = ctxfuse::test::scratch_dir("score_authors");
  for (const char* who : {"LS", "ESKF"}) {
    const auto r = run("score --estimate " + q(dir / (std::string(who) + ".csv")) + " --reference " + q(dir / "trajectory.csv") +
                       " --span a --json " + q(tmp / "s.json"));
    ASSERT_EQ(r.code, 0) << r.err;
    const json j = read_json(tmp / "s.json");
    EXPECT_EQ(j.at("protocol"), "trajectory_a");
    // Their own figure, from their RMSD_results.txt ("LS RMSE_2d: 0.97754..."); agreement to
    // 4e-8 m (their ns stamps against our seconds in doubles; tests/pipelines/nlos_uwb_eval_test).
    const auto theirs = ctxfuse::studies::read_hanyang_rmsd(dir / "RMSD_results.txt");
    EXPECT_NEAR(j.at("rmse_2d_m").get<double>(), theirs.at(std::string(who) + " RMSE_2d"), 1e-6) << who;
  }
  fs::remove_all(tmp);
}

TEST(CliScore, HandComputedSpansAndWholeRun) {
  const fs::path tmp = ctxfuse::test::scratch_dir("score_hand");
  // Trajectory B's gates (start x < 8.6, y < -7; end x > 8.6, y < -7); t = 3 has |z| >= 0.5.
  std::ofstream(tmp / "ref.csv") << "timestamp,x,y,z,heading_degrees\n0,10,-8,0,0\n1e9,8,-8,0,0\n2e9,5,0,0,0\n3e9,6,2,0.8,0\n4e9,9,-8,0,0\n"
                                    "5e9,20,0,0,0\n";
  // Errors^2 in span B: 1, 1, 0, 9, 4 (sum 15 over 5); whole run: 0, 1, 1, 37, 0.25, 4, 9 (52.25 over 7).
  std::ofstream(tmp / "est.csv") << "time_ns,x,y,z\n500000000,9,-8,1\n1000000000,8,-7,1\n1500000000,6.5,-3,1\n3000000000,7,-4,1\n"
                                    "3500000000,8,-3,1\n4000000000,11,-8,1\n4500000000,14.5,-1,1\n6000000000,0,0,1\n";
  struct Case {
    std::string span, protocol;
    double rmse;
    std::size_t scored;
    bool warns;
  };
  for (const Case& c : {Case{"b", "trajectory_b", std::sqrt(3.0), 5, false}, Case{"auto", "trajectory_b", std::sqrt(3.0), 5, false},
                        Case{"\"x<8.6,y<-7/x>8.6,y<-7\"", "custom", std::sqrt(3.0), 5, false},
                        Case{"none", "whole_run", std::sqrt(52.25 / 7.0), 7, false},
                        Case{"a", "whole_run", std::sqrt(52.25 / 7.0), 7, true}}) {
    const auto r = run("score --estimate " + q(tmp / "est.csv") + " --reference " + q(tmp / "ref.csv") + " --span " + c.span + " --json " +
                       q(tmp / "s.json"));
    ASSERT_EQ(r.code, 0) << c.span << r.err;
    const json j = read_json(tmp / "s.json");
    EXPECT_EQ(j.at("protocol"), c.protocol) << c.span;
    EXPECT_NEAR(j.at("rmse_2d_m").get<double>(), c.rmse, 1e-12) << c.span;
    EXPECT_EQ(j.at("scored").get<std::size_t>(), c.scored) << c.span;
    EXPECT_EQ(r.err.find("warning") != std::string::npos, c.warns) << c.span << r.err;
    EXPECT_NE(r.out.find("2-D RMSE"), std::string::npos);
  }
  EXPECT_EQ(run("score --estimate " + q(tmp / "est.csv") + " --reference " + q(tmp / "ref.csv") + " --span q").code, 2);
  EXPECT_EQ(run("score --estimate " + q(tmp / "missing.csv") + " --reference " + q(tmp / "ref.csv")).code, 2);
  // The files swapped: the reference's float stamps are not the integer ns of an estimate.
  const auto swapped = run("score --estimate " + q(tmp / "ref.csv") + " --reference " + q(tmp / "est.csv"));
  EXPECT_EQ(swapped.code, 1);
  EXPECT_NE(swapped.err.find("ref.csv:3:1: column 'timestamp'"), std::string::npos) << swapped.err;
  // A reference without its heading column.
  std::ofstream(tmp / "short.csv") << "timestamp,x,y,z\n0,0,0,0\n1e9,1,1,0\n";
  const auto no_heading = run("score --estimate " + q(tmp / "est.csv") + " --reference " + q(tmp / "short.csv"));
  EXPECT_EQ(no_heading.code, 1);
  EXPECT_NE(no_heading.err.find("heading_degrees"), std::string::npos) << no_heading.err;
  fs::remove_all(tmp);
}

TEST(CliRunUwbAny, SimulatedIndoorYardBelowLeastSquares) {
  namespace sim = ctxfuse::sim;
  const fs::path tmp = ctxfuse::test::scratch_dir("run_uwb_yard");
  sim::WalkConfig w;
  w.walk_s = 60.0;
  w.t0 = 1.7e9;  // a Unix-time clock, as the recordings have
  const auto path = sim::pedestrian_walk(w);
  sim::UwbSiteConfig c;
  const double xy[8][2] = {{-1, -1}, {10, -1}, {21, -1}, {21, 10}, {21, 21}, {10, 21}, {-1, 21}, {-1, 10}};
  for (int k = 0; k < 8; ++k) c.anchors.push_back({k + 1, {xy[k][0], xy[k][1], k % 2 ? 2.0 : 0.5}, 100.0, 0.0005 * k, 0.10 + 0.2 * k / 7.0});
  c.rate_jitter_s = 0.0003;
  c.seed = 11;
  ctxfuse::io::write_hanyang_case(tmp / "yard", sim::simulate_uwb_site(path, c), sim::hanyang_reference(path, w.tag_height_m));
  const auto r = run("run uwb --data " + q(tmp / "yard") + " --out " + q(tmp / "t.csv") + " --json " + q(tmp / "y.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: span auto: neither"), std::string::npos) << r.err;
  const json j = read_json(tmp / "y.json");
  EXPECT_EQ(j.at("settings").at("range_average_samples"), 1);
  EXPECT_NEAR(j.at("settings").at("range_period_s").get<double>(), 0.01, 1e-4);
  EXPECT_EQ(j.at("recording").at("anchors").size(), 8u);
  EXPECT_EQ(j.at("scoring").at("protocol"), "whole_run");
  const double ekf = j.at("rmse_2d_m").at("calibrated_ekf_gate_per_range"), ls = j.at("rmse_2d_m").at("least_squares");
  std::printf("simulated yard via the CLI: calibrated_ekf_gate_per_range %.4f m, least_squares %.4f m\n", ekf, ls);
  EXPECT_LT(ekf, 0.5 * ls);
  // `score` on the written trajectory gives the run's figure.
  const auto s = run("score --estimate " + q(tmp / "t.csv") + " --reference " + q(tmp / "yard" / "trajectory.csv") + " --span none --json " +
                     q(tmp / "s.json"));
  ASSERT_EQ(s.code, 0) << s.err;
  EXPECT_NEAR(read_json(tmp / "s.json").at("rmse_2d_m").get<double>(), ekf, 1e-6);
  fs::remove_all(tmp);
}

}  // namespace run_uwb_any_cli

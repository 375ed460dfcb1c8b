// Runs the built `ctxfuse` binary: exit codes and messages of demo / sim / run, and malformed
// logs that must end in a clear message naming file, line and field (never a crash).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/plot_data.hpp"
#include "support/run_cli.hpp"

namespace fs = std::filesystem;

// Named, not anonymous: the area's sources share one unity build (tests/CMakeLists.txt).
namespace cli_commands_cli {

ctxfuse::test::CliRun run(const std::string& args) { return ctxfuse::test::run_cli(args); }

// One folder per process: ctest runs test cases in parallel processes (and several build
// trees may test at once), so a fixed name would let one test rewrite another's logs.
fs::path scratch(const std::string& name) {
  const auto p = fs::temp_directory_path() / ("ctxfuse_cli_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  return p;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Replaces line `line` (1-based) of a file.
void replace_line(const fs::path& p, int line, const std::string& text) {
  std::istringstream in(slurp(p));
  std::ostringstream out;
  std::string l;
  for (int i = 1; std::getline(in, l); ++i) out << (i == line ? text : l) << '\n';
  std::ofstream(p) << out.str();
}

const fs::path& logs() {
  static const fs::path dir = [] {
    auto d = scratch("logs");
    const auto r = run("sim --seed 4 --out \"" + d.string() + "\"");
    EXPECT_EQ(r.code, 0) << r.out;
    return d;
  }();
  return dir;
}

TEST(CliSim, WritesAllSevenLogs) {
  const auto& d = logs();
  for (const char* f : {"imu.csv", "gnss.csv", "sats.csv", "uwb.csv", "speed.csv", "mag.csv", "truth.csv"})
    EXPECT_GT(fs::file_size(d / f), 100u) << f;
  EXPECT_EQ(slurp(d / "imu.csv").substr(0, 8), "t,gyro_x");
}

// A real option out of its range is named in words; CLI11's own PositiveNumber wrote out the
// largest double in full.
TEST(CliOptions, RealOutOfRangeSaidInWords) {
  for (const char* v : {"-1", "0", "nan", "inf", "2x"}) {
    const auto r = run(std::string("run gins --data /tmp --gnss-rate ") + v);
    EXPECT_EQ(r.code, 2) << v;
    EXPECT_NE(r.out.find(std::string("--gnss-rate: '") + v + "' is not a positive number"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("1797693"), std::string::npos) << r.out;
  }
  const auto r = run("classify train --gamma -0.5");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--gamma: '-0.5' is not a non-negative number"), std::string::npos) << r.out;
}

TEST(CliSim, UsageErrors) {
  auto r = run("sim --seed 1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--out is required"), std::string::npos) << r.out;
  r = run("sim --seed abc --out /tmp/x");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--seed: 'abc' is not a non-negative integer"), std::string::npos) << r.out;
  r = run("sim --seed -3 --out /tmp/x");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--seed: '-3' is not a non-negative integer"), std::string::npos) << r.out;
  r = run("sim --bogus 1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("unknown option '--bogus'"), std::string::npos) << r.out;
  r = run("sim --duration 5 --out /tmp/x");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("duration_s"), std::string::npos) << r.out;
}

TEST(CliRun, GnssBaselineScoresAgainstTruth) {
  const auto out = scratch("run_out");
  fs::create_directories(out);
  const auto r = run("run gnss --data \"" + logs().string() + "\" --json \"" + (out / "r.json").string() + "\" --out \"" +
                     (out / "traj.csv").string() + "\"");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("outdoor"), std::string::npos);
  const auto json = slurp(out / "r.json");
  EXPECT_NE(json.find("\"rmse_h_m\""), std::string::npos);
  EXPECT_NE(json.find("\"transition\""), std::string::npos);
  // One trajectory row per fix, and fixes exist only outside the garage.
  const auto traj = slurp(out / "traj.csv");
  EXPECT_EQ(traj.substr(0, 16), "t,east,north,up\n");
  const auto gnss = slurp(logs() / "gnss.csv");
  std::istringstream g(gnss);
  std::string line;
  std::getline(g, line);
  int fixes = 0;
  while (std::getline(g, line)) fixes += line.find(",1,") == line.find(',') ? 1 : 0;
  int rows = -1;
  std::istringstream t(traj);
  while (std::getline(t, line)) ++rows;
  EXPECT_EQ(rows, fixes);
  EXPECT_GT(fixes, 100);
}

TEST(CliRun, UnknownPipelineListsTheAvailableOnes) {
  const auto r = run("run nosuch --data /tmp");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("unknown pipeline 'nosuch'"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Pipelines and the files they read"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("region-imm"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("gnss"), std::string::npos) << r.out;
  EXPECT_EQ(run("run gnss").code, 2);
}

TEST(CliRun, MalformedLogsNameFileLineAndField) {
  struct Case {
    const char* file;
    int line;
    const char* text;
    const char* expect;
  } cases[] = {
      {"imu.csv", 5, "0.04,0.1,abc,0,0,0,9.8", "imu.csv:5:3: column 'gyro_y': 'abc' is not a number"},
      {"imu.csv", 7, "0.06,0.1,0,0,nan,0,9.8", "imu.csv:7:5: column 'accel_x': 'nan' is not finite"},
      {"imu.csv", 9, "0.001,0,0,0,0,0,9.8", "imu.csv:9:1: column 't': time 0.001 is not after the previous row's"},
      {"gnss.csv", 3, "2,1,3", "gnss.csv:3: 3 fields, expected 11 (as in the header)"},
      {"uwb.csv", 1, "time,anchor", "uwb.csv:1: header is 'time,anchor'"},
      {"truth.csv", 4, "0.03,0,0,0,0,0,0,0,0,0,0,0,0,0,0,9.8,0,7,0,0", "truth.csv:4:18: column 'region': '7' is outside the allowed range [0, 2]"},
      {"sats.csv", 2, "", "sats.csv"},
  };
  for (const auto& c : cases) {
    const auto dir = scratch(std::string("bad_") + c.file + std::to_string(c.line));
    fs::copy(logs(), dir);
    replace_line(dir / c.file, c.line, c.text);
    const auto r = run("run gnss --data \"" + dir.string() + "\"");
    EXPECT_EQ(r.code, 1) << c.file << ":\n" << r.out;
    EXPECT_NE(r.out.find(c.expect), std::string::npos) << "expected '" << c.expect << "' in:\n" << r.out;
    fs::remove_all(dir);
  }
  // A missing file and a binary file.
  const auto dir = scratch("bad_missing");
  fs::copy(logs(), dir);
  fs::remove(dir / "speed.csv");
  auto r = run("run gnss --data \"" + dir.string() + "\"");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.out.find("speed.csv: cannot open file"), std::string::npos) << r.out;
  {
    std::ofstream(dir / "speed.csv", std::ios::binary) << std::string("\x00\x01\xff\xfe garbage", 12);
  }
  r = run("run gnss --data \"" + dir.string() + "\"");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.out.find("speed.csv:1: header is"), std::string::npos) << r.out;
  fs::remove_all(dir);
}

TEST(CliDemo, SummaryJsonAndSectionsNotBuilt) {
  const auto out = scratch("demo");
  fs::create_directories(out);
  const auto r = run("demo --seed 2 --json \"" + (out / "demo.json").string() + "\"");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("Simulated drive (seed 2)"), std::string::npos) << r.out;
  const auto json = slurp(out / "demo.json");
  EXPECT_NE(json.find("\"drive\""), std::string::npos);
  EXPECT_NE(json.find("\"region_shares\""), std::string::npos);
  // Each paper's section either ran (its key in the JSON) or printed "not built" (and left
  // nothing in the JSON): the two counts add up to the five sections.
  int in_json = 0, not_built = 0;
  for (const char* key : {"region_imm", "scene_gins", "nlos_uwb", "phone_gins", "latency_us"})
    in_json += json.find(std::string("\"") + key + "\"") != std::string::npos ? 1 : 0;
  for (auto pos = r.out.find(": not built\n"); pos != std::string::npos; pos = r.out.find(": not built\n", pos + 1)) ++not_built;
  EXPECT_EQ(in_json + not_built, 5) << r.out;
  // Paper C's sections: the protocol's tables beside the paper's and the indicative timing.
  for (const char* key : {"\"nlos_share\"", "\"identification\"", "\"svm_vu\"", "\"graph_paper_rule\"", "\"graph_imu_paper_rule\"", "\"imu_only\"",
                          "\"cdf_east_m\"", "\"total_paper\"", "\"indicative\""})
    EXPECT_NE(json.find(key), std::string::npos) << key;
  EXPECT_NE(r.out.find("SVM (v_u, v_i)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("0.899/1.873/0.872 (proposed)"), std::string::npos) << r.out;
  EXPECT_EQ(run("demo --seed -3").code, 2);
}

// Papers B and D: the demo's scene_gins and phone_gins sections print the GNSS/INS study of the
// demo's drive, the same numbers `ctxfuse gins-study` computes for that seed, beside the papers'.
TEST(CliDemo, GinsSectionsAreTheStudyOfTheDemosDrive) {
  const auto dir = scratch("demo_gins");
  fs::create_directories(dir);
  const auto demo = run("demo --seed 2 --json \"" + (dir / "demo.json").string() + "\"");
  ASSERT_EQ(demo.code, 0) << demo.out;
  const auto study = run("gins-study --seeds 2 --json \"" + (dir / "study.json").string() + "\"");
  ASSERT_EQ(study.code, 0) << study.out;
  EXPECT_NE(demo.out.find("Scene-adaptive GNSS/INS (paper B)"), std::string::npos) << demo.out;
  EXPECT_NE(demo.out.find("131.52 / 669.86"), std::string::npos) << demo.out;
  std::ifstream dj(dir / "demo.json"), sj(dir / "study.json");
  const nlohmann::json d = nlohmann::json::parse(dj), st = nlohmann::json::parse(sj).at("per_seed").at(0);
  // Every run of the study, found under its section's key, with the same errors and fix counts.
  const std::pair<const char*, const char*> schemes[] = {{"(a)", "a_gnss_ins"}, {"(b)", "b_rts"}, {"(c)", "c_constraints"},
                                                         {"(d)", "d_constraints_rts"}, {"(c')", "c_constraints_zihr"},
                                                         {"(d')", "d_constraints_zihr_rts"}};
  const std::pair<const char*, const char*> noises[] = {{"fixed", "fixed"}, {"scene (classifier)", "scene_classifier"}};
  int compared = 0;
  for (const auto& run_json : st.at("runs")) {
    const std::string scheme = run_json.at("scheme"), noise = run_json.at("noise");
    const auto prefix = scheme.substr(0, scheme.find(' '));
    for (const auto& [sp, skey] : schemes) {
      if (prefix != sp) continue;
      for (const auto& [np, nkey] : noises) {
        if (noise != np) continue;
        const auto& row = d.at("phone_gins").at("schemes").at(skey).at(nkey);
        for (const char* part : {"all", "with_gnss", "indoor"})
          for (const char* stat : {"rms_m", "p67_m", "p75_m", "max_m"})
            EXPECT_EQ(row.at(part).at(stat), run_json.at(part).at(stat)) << scheme << " " << noise << " " << part << " " << stat;
        EXPECT_EQ(row.at("fixes_used"), run_json.at("fixes_used")) << scheme << " " << noise;
        ++compared;
      }
    }
    if (prefix == "(a)") {
      const std::string key = noise == "fixed" ? "fixed" : noise == "scene (true)" ? "scene_true" : "scene_classifier";
      EXPECT_EQ(d.at("scene_gins").at("gnss_ins").at(key).at("all").at("p67_m"), run_json.at("all").at("p67_m")) << noise;
      ++compared;
    }
  }
  EXPECT_EQ(compared, 6 * 2 + 3);
  EXPECT_EQ(d.at("scene_gins").at("scene_accuracy"), st.at("scene_accuracy"));
  EXPECT_EQ(d.at("phone_gins").at("false_static_share_odometer"), st.at("false_static_share_odometer"));
  EXPECT_EQ(d.at("scene_gins").at("gnss_ins").at("fixed").at("paper_p67_m"), 11.23);
  EXPECT_EQ(d.at("phone_gins").at("schemes").at("d_constraints_rts").at("paper_p75_m"), 7.09);
  fs::remove_all(dir);
}

TEST(CliDemo, PlotsArePngFilesOrAClearMessage) {
  const auto dir = scratch("plots");
  const auto r = run("demo --seed 1 --plot \"" + dir.string() + "\" --json \"" + (dir / "demo.json").string() + "\"");
  ASSERT_EQ(r.code, 0) << r.out;
  if (r.out.find("gnuplot not found") != std::string::npos) GTEST_SKIP() << "gnuplot is not installed";
  for (const char* f : {"drive_trajectory.png", "gnss_error_cdf.png"}) {
    ASSERT_TRUE(fs::exists(dir / f)) << f << "\n" << r.out;
    EXPECT_EQ(slurp(dir / f).substr(1, 3), "PNG") << f;
  }
  // Section nlos_uwb: the gated graph with the paper's rule; its plotted errors over the scored
  // span are its table row's, and its left-out epochs are the row's count.
  std::ifstream js(dir / "demo.json");
  const nlohmann::json doc = nlohmann::json::parse(js);
  if (!doc.contains("nlos_uwb")) GTEST_SKIP() << "section nlos_uwb not built";
  namespace t = ctxfuse::test;
  const auto& row = doc.at("nlos_uwb").at("positioning").at("graph_gate_paper_rule");
  const std::string v = "graph_gate_paper_rule";
  const auto traj = t::expect_plot(dir, "nlos_uwb_trajectory");
  EXPECT_EQ(static_cast<double>(traj.at(v + ", left-out epochs").size()), row.at("epochs_left_out").get<double>());
  EXPECT_GT(traj.at("UWB anchors").size(), 0u);
  const auto err = t::expect_plot(dir, "nlos_uwb_error_time");
  const auto& e = err.at(v + " 2-D error");
  EXPECT_EQ(static_cast<double>(e.size()), row.at("count").get<double>());
  EXPECT_NEAR(t::rms_y(e), row.at("rmse_h_m").get<double>(), t::six_digits(row.at("rmse_h_m")));
  EXPECT_NEAR(t::max_y(e), row.at("max_h_m").get<double>(), t::six_digits(row.at("max_h_m")));
  if (err.count("left-out epochs")) {
    for (const auto& p : err.at("left-out epochs")) EXPECT_NE(std::find(e.begin(), e.end(), p), e.end()) << p.first;
  }
  const auto cdf = t::expect_plot(dir, "nlos_uwb_error_cdf");
  for (const char* name : {"graph_gate_paper_rule", "least_squares", "graph", "graph_paper_rule", "graph_imu_paper_rule", "ekf_gate_paper_rule"}) {
    ASSERT_TRUE(cdf.count(name)) << name;
    EXPECT_EQ(static_cast<double>(cdf.at(name).size()), doc.at("nlos_uwb").at("positioning").at(name).at("count").get<double>()) << name;
  }
}

}  // namespace cli_commands_cli

// `ctxfuse run gins` on recordings nobody tuned it on: the simulated walk and robot written by
// `ctxfuse sim --platform` in the real formats (RTKLIB .pos, IMU csv + .tag; UWB in the Hanyang
// layout), each run with and without its reference; --platform's constraints and its refusal of NHC on a walker; the real
// drive scored against a --reference file; and the real drive's IMU csv cut at 1 MB beside its
// whole .tag, which runs on the part it has at its true rate and says so.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "support/data_dir.hpp"
#include "support/run_cli.hpp"

namespace fs = std::filesystem;

// Named, not anonymous: the area's sources share one unity build (tests/CMakeLists.txt).
namespace run_gins_platform_cli {

ctxfuse::test::CliRun run(const std::string& args) { return ctxfuse::test::run_cli(args, ctxfuse::test::Stderr::separate); }

nlohmann::json read_json(const fs::path& p) {
  std::ifstream is(p);
  return nlohmann::json::parse(is);
}

std::size_t rows_of(const fs::path& csv) {
  std::ifstream is(csv);
  std::string line;
  std::size_t n = 0;
  while (std::getline(is, line)) ++n;
  return n == 0 ? 0 : n - 1;  // less the header
}

void check_platform(const std::string& platform, double max_rms_m) {
  const fs::path dir = ctxfuse::test::scratch_dir("run_gins_" + platform);
  const fs::path rec = dir / "recording";
  const auto sim = run("sim --platform " + platform + " --seed 3 --out \"" + rec.string() + "\"");
  ASSERT_EQ(sim.code, 0) << sim.err;
  ASSERT_TRUE(fs::exists(rec / "gnss.pos") && fs::exists(rec / "imu.csv") && fs::exists(rec / "imu.csv.tag"));
  ASSERT_TRUE(fs::exists(rec / "reference" / "truth.pos"));
  // Without a reference: a trajectory and the JSON of what the run did, nothing scored.
  const auto bare = run("run gins --data \"" + rec.string() + "\" --platform " + platform + " --out \"" + (dir / "b.csv").string() +
                        "\" --json \"" + (dir / "b.json").string() + "\"");
  ASSERT_EQ(bare.code, 0) << bare.err;
  const auto b = read_json(dir / "b.json");
  EXPECT_FALSE(b.contains("forward")) << "scored without a reference";
  EXPECT_FALSE(b.contains("whole_run"));
  EXPECT_EQ(b.at("platform").get<std::string>(), platform);
  EXPECT_EQ(b.at("constraints").get<std::string>(), platform == "pedestrian" ? "zupt" : "zupt,nhc");
  EXPECT_TRUE(b.at("alignment").at("levelled_on_static_start").get<bool>());
  // The static test's thresholds from the recording's own 10-12 s at rest: the simulated IMU's
  // white noise (0.0038 deg/s/sqrt(Hz) is the floor) gives far less than the fallback's 0.25.
  const auto& th = b.at("static_thresholds");
  EXPECT_EQ(th.at("source").get<std::string>(), "static start");
  EXPECT_LT(th.at("gyro_dps").get<double>(), 0.25);
  EXPECT_GT(th.at("gyro_dps").get<double>(), 4.03 * 0.0038 / std::sqrt(0.5));
  EXPECT_LT(th.at("accel_mps2").get<double>(), 0.25);
  EXPECT_EQ(b.at("imu_time_mapping").at("method").get<std::string>(), "scaled");
  // The simulated clock runs 40 ppm fast; the tag's mapping sees that and the start latency.
  EXPECT_LT(std::abs(b.at("imu_time_mapping").at("scale_ppm").get<double>()), 100.0);
  EXPECT_EQ(rows_of(dir / "b.csv"), b.at("epochs").get<std::size_t>());
  EXPECT_GT(rows_of(dir / "b.csv"), 1000u);  // 4 Hz over most of 300 s
  // With the truth as the reference: the outage protocol and the whole run.
  const auto scored = run("run gins --data \"" + rec.string() + "\" --platform " + platform +
                          " --gnss-rate 1 --outage 15:45:40 --reference \"" + (rec / "reference" / "truth.pos").string() +
                          "\" --json \"" + (dir / "c.json").string() + "\"");
  ASSERT_EQ(scored.code, 0) << scored.err;
  const auto c = read_json(dir / "c.json");
  EXPECT_GE(c.at("outages_scored").get<int>(), 4);
  EXPECT_LT(c.at("forward").at("rms_m").get<double>(), max_rms_m) << platform;
  EXPECT_GT(c.at("whole_run").at("forward").at("epochs").get<int>(), 1000);
  EXPECT_LT(c.at("whole_run").at("forward").at("rms_m").get<double>(), c.at("forward").at("rms_m").get<double>());
  // The same run's UWB site in the Hanyang layout: `run uwb` reads it unchanged, with its
  // reference (scored over the whole run: no Hanyang span fits the yard) and without one.
  const auto u = run("run uwb --data \"" + (rec / "uwb").string() + "\" --json \"" + (dir / "u.json").string() + "\"");
  ASSERT_EQ(u.code, 0) << u.err;
  const auto uj = read_json(dir / "u.json");
  EXPECT_EQ(uj.at("recording").at("anchors").size(), 8u);
  EXPECT_EQ(uj.at("scoring").at("protocol"), "whole_run");
  const double ekf = uj.at("rmse_2d_m").at("calibrated_ekf_gate_per_range"), ls = uj.at("rmse_2d_m").at("least_squares");
  std::printf("%s's UWB site: calibrated_ekf_gate_per_range %.4f m, least_squares %.4f m\n", platform.c_str(), ekf, ls);
  EXPECT_LT(ekf, 0.5 * ls);
  const fs::path lone = dir / "uwb_alone";
  fs::create_directories(lone);
  for (const auto& e : fs::directory_iterator(rec / "uwb"))
    if (e.path().filename().string().starts_with("A")) fs::copy_file(e.path(), lone / e.path().filename());
  const auto ua = run("run uwb --data \"" + lone.string() + "\" --out \"" + (dir / "u.csv").string() + "\" --json \"" +
                      (dir / "ua.json").string() + "\"");
  ASSERT_EQ(ua.code, 0) << ua.err;
  EXPECT_FALSE(read_json(dir / "ua.json").contains("rmse_2d_m"));
  EXPECT_GT(rows_of(dir / "u.csv"), 1000u);
  fs::remove_all(dir);
}

TEST(CliRunGinsPlatforms, TheSimulatedWalkRunsWithAndWithoutItsReference) { check_platform("pedestrian", 2.0); }

TEST(CliRunGinsPlatforms, TheSimulatedRobotRunsWithAndWithoutItsReference) { check_platform("robot", 0.6); }

TEST(CliRunGinsPlatforms, NhcIsRefusedOnAWalker) {
  const auto r = run("run gins --data . --platform pedestrian --constraints zupt,nhc");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("wheeled"), std::string::npos) << r.err;
}

TEST(CliRunGinsPlatforms, TheRealDriveScoredAgainstAReferenceFileAndItsCutCsv) {
  CTXFUSE_REQUIRE_DATA(drive, "gnss-imu-drive");
  const fs::path dir = ctxfuse::test::scratch_dir("run_gins_cut");
  const char* inst = " --imu-rpy 180,-6.79,185.35 --imu-lever 0,0,-0.65 --gnss-lever 0,-0.05,-0.65 --imu-delay -0.125";
  // --reference: the drive's own .pos named as a file gives the same outage scores as the
  // default, and a whole-run figure.
  const auto ref = run("run gins --data \"" + drive.string() + "\"" + inst + " --platform car --outage 15:45:40 --gnss-rate 1 --reference \"" +
                       (drive / "gnss_1934_sf.pos").string() + "\" --json \"" + (dir / "r.json").string() + "\"");
  ASSERT_EQ(ref.code, 0) << ref.err;
  const auto r = read_json(dir / "r.json");
  EXPECT_NEAR(r.at("forward").at("rms_m").get<double>(), 1.025, 0.02);  // docs/results.md gins_real, zupt,nhc
  EXPECT_EQ(r.at("constraints").get<std::string>(), "zupt,nhc");
  EXPECT_GT(r.at("whole_run").at("forward").at("epochs").get<int>(), 1900);  // the RTK-fixed epochs after the alignment (55 s in)
  // The IMU csv cut at 1 MB (mid-line) beside the whole tag: run on the part it has, at its
  // true rate (about 100 Hz, not the 40 Hz a stretch over the tag's span would give), and say
  // the mapping on stderr and in the JSON.
  const fs::path cut = dir / "cut";
  fs::create_directories(cut);
  fs::copy_file(drive / "gnss_1934_sf.pos", cut / "gnss_1934_sf.pos");
  fs::copy_file(drive / "imu_1934.csv.tag", cut / "imu_1934.csv.tag");
  {
    std::ifstream in(drive / "imu_1934.csv", std::ios::binary);
    std::string bytes(1'000'000, '\0');
    in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    std::ofstream(cut / "imu_1934.csv", std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  const auto c = run("run gins --data \"" + cut.string() + "\"" + inst + " --platform car --json \"" + (dir / "c.json").string() + "\"");
  ASSERT_EQ(c.code, 0) << c.err;
  EXPECT_NE(c.err.find("cut short"), std::string::npos) << c.err;
  const auto j = read_json(dir / "c.json");
  EXPECT_EQ(j.at("imu_time_mapping").at("method").get<std::string>(), "nominal");
  EXPECT_NEAR(j.at("imu_rate_hz").get<double>(), 100.0, 0.5);
  EXPECT_EQ(j.at("imu_time_mapping").at("partial_lines").get<int>(), 1);
  EXPECT_GT(j.at("streams").at("gnss").at("beyond_imu").get<int>(), 1000);  // the fixes after the IMU ends
  fs::remove_all(dir);
}

}  // namespace run_gins_platform_cli

// `ctxfuse run gins`: usage errors name the problem (exit 2), a folder without the recording's
// files is a runtime error (exit 1); on the real drive (skipped without it) the trajectory CSV,
// scored again here with the outage protocol, gives the JSON's figure; --plot writes its three
// plots, whose data agree with the JSON's outage scores.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli/plot_data.hpp"
#include "ctxfuse/studies/gins_outages.hpp"
#include "support/data_dir.hpp"
#include "support/run_cli.hpp"

namespace fs = std::filesystem;

// Named, not anonymous: the area's sources share one unity build (tests/CMakeLists.txt).
namespace run_gins_cli {

ctxfuse::test::CliRun run(const std::string& args) { return ctxfuse::test::run_cli(args, ctxfuse::test::Stderr::separate); }

const char* kDrive = " --imu-rpy 180,-6.79,185.35 --imu-lever 0,0,-0.65 --gnss-lever 0,-0.05,-0.65 --imu-delay -0.125";

TEST(CliRunGins, UsageErrorsNameTheProblem) {
  const fs::path empty = fs::temp_directory_path() / ("ctxfuse_run_gins_empty_" + std::to_string(::getpid()));
  fs::create_directories(empty);
  const std::string data = " --data \"" + empty.string() + "\"";
  struct Case {
    std::string args, says;
  };
  const std::vector<Case> cases{
      {"--outage 15:45", "LEN:PERIOD:START"},
      {"--outage 15:45:x", "'x'"},
      {"--outage 0:45:40", "length"},
      {"--outage 15:10:40", "period"},
      {"--constraints zupt,foo", "unknown constraint 'foo'"},
      {"--constraints ''", "--constraints"},
      {"--imu-rpy 1,2", "--imu-rpy"},
      {"--gnss-lever 0,0,nan", "finite"},
      {"--gnss-rate -1", "--gnss-rate"},
      {"--imu-delay abc", "--imu-delay"},
      {"--imu-noise 0.1", "--imu-noise"},
      {"--imu-noise -0.1,0.01", "--imu-noise"},
      {"--plane", "unknown option '--plane'"},
  };
  for (const auto& c : cases) {
    const auto r = run("run gins" + data + " " + c.args);
    EXPECT_EQ(r.code, 2) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << c.args << ": " << r.err;
  }
  const auto no_files = run("run gins" + data);
  EXPECT_EQ(no_files.code, 1);
  EXPECT_NE(no_files.err.find("expected one *.pos file, found 0"), std::string::npos) << no_files.err;
  fs::remove_all(empty);
}

TEST(CliRunGins, MagnetometerConstraintNeedsTheFolderToHoldOne) {
  CTXFUSE_REQUIRE_DATA(dir, "gnss-imu-drive");  // no mag*.csv there
  const auto r = run("run gins --data \"" + dir.string() + "\" --constraints zupt,mag");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("constraint 'mag' needs a magnetometer stream: no mag*.csv in"), std::string::npos) << r.err;
}

// The drive's files and a mag.csv beside them whose field is fixed in the IMU's axes (the drive
// has no magnetometer): a field that says the car never turns. Asked for, it is read and
// replayed (updates while the heading holds, refused by the gate in the turns); not asked
// for, it changes nothing.
TEST(CliRunGins, MagnetometerFileIsReplayedOnlyWhenAsked) {
  CTXFUSE_REQUIRE_DATA(dir, "gnss-imu-drive");
  const fs::path tmp = ctxfuse::test::scratch_dir("run_gins_mag");
  for (const char* f : {"gnss_1934_sf.pos", "imu_1934.csv", "imu_1934.csv.tag"}) fs::create_symlink(dir / f, tmp / f);
  const auto fixes = ctxfuse::io::to_gnss_fixes(ctxfuse::io::read_rtklib_pos(dir / "gnss_1934_sf.pos"));
  {
    std::ofstream mag(tmp / "mag.csv");
    mag << "t,mag_x,mag_y,mag_z\n";
    for (double t = fixes.front().t - 30.0; t < fixes.back().t; t += 0.1) mag << ctxfuse::io::cat(t) << ",20,5,40\n";
  }
  auto metrics = [&](const std::string& constraints) {
    const auto r = run("run gins --data \"" + tmp.string() + "\"" + kDrive + " --outage 15:45:40 --gnss-rate 1 --constraints " +
                       constraints + " --json \"" + (tmp / "m.json").string() + "\"");
    EXPECT_EQ(r.code, 0) << r.err;
    std::ifstream js(tmp / "m.json");
    return nlohmann::json::parse(js);
  };
  const nlohmann::json with = metrics("zupt,nhc,mag"), without = metrics("zupt,nhc");
  EXPECT_GT(with.at("counts").at("mag").get<int>(), 0);
  EXPECT_GT(with.at("counts").at("mag_gated").get<int>(), 0);
  EXPECT_EQ(without.at("counts").at("mag").get<int>() + without.at("counts").at("mag_gated").get<int>(), 0);
  EXPECT_NEAR(without.at("forward").at("rms_m").get<double>(), 1.025, 0.02);  // the drive's figure, file or not
  fs::copy_file(tmp / "mag.csv", tmp / "mag_2.csv");
  const auto two = run("run gins --data \"" + tmp.string() + "\" --constraints mag");
  EXPECT_EQ(two.code, 1);
  EXPECT_NE(two.err.find("expected at most one mag*.csv file, found 2"), std::string::npos) << two.err;
  fs::remove_all(tmp);
}

TEST(CliRunGins, OutagesOnTheRealDriveCsvAndJsonAgree) {
  CTXFUSE_REQUIRE_DATA(dir, "gnss-imu-drive");
  const fs::path tmp = ctxfuse::test::scratch_dir("run_gins");
  const auto r = run("run gins --data \"" + dir.string() + "\"" + kDrive +
                     " --outage 15:45:40 --gnss-rate 1 --constraints zupt,nhc --smooth --out \"" + (tmp / "traj.csv").string() +
                     "\" --json \"" + (tmp / "m.json").string() + "\"");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("smoothed"), std::string::npos) << r.out;
  std::ifstream js(tmp / "m.json");
  const nlohmann::json doc = nlohmann::json::parse(js);
  EXPECT_EQ(doc.at("outages_scored").get<int>(), 10);
  EXPECT_EQ(doc.at("forward").at("outages").size(), 11u);
  const double fwd = doc.at("forward").at("rms_m"), smoothed = doc.at("smoothed").at("rms_m");
  EXPECT_NEAR(fwd, 1.025, 0.02);
  EXPECT_NEAR(smoothed, 0.288, 0.005);
  EXPECT_EQ(doc.at("static_start").at("samples").get<int>(), 3061);
  EXPECT_NEAR(doc.at("static_start").at("gyro_allan_1s_dps").at(1).get<double>(), 0.0991, 0.0001);
  EXPECT_EQ(doc.at("counts").at("imu_losses").get<int>(), 0);

  // --imu-noise replaces the settings' densities: the static start's scatter read as white
  // noise (docs/results.md "gins_real", the sensitivity row).
  const auto scatter = run("run gins --data \"" + dir.string() + "\"" + kDrive +
                           " --outage 15:45:40 --gnss-rate 1 --constraints zupt,nhc --imu-noise 0.233,0.013 --json \"" +
                           (tmp / "scatter.json").string() + "\"");
  ASSERT_EQ(scatter.code, 0) << scatter.err;
  std::ifstream sj(tmp / "scatter.json");
  EXPECT_NEAR(nlohmann::json::parse(sj).at("forward").at("rms_m").get<double>(), 2.511, 0.02);

  // The CSV (the smoothed trajectory) read back and scored again.
  std::ifstream csv(tmp / "traj.csv");
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  EXPECT_EQ(line.rfind("gps_s,lat_deg,lon_deg,height_m,vn,ve,vd,roll_deg,pitch_deg,yaw_deg,", 0), 0u) << line;
  std::vector<ctxfuse::studies::TimedLatLon> traj;
  constexpr double deg = 3.14159265358979323846 / 180.0;
  while (std::getline(csv, line)) {
    std::stringstream ss(line);
    std::string f[3];
    for (auto& s : f) std::getline(ss, s, ',');
    traj.push_back({std::stod(f[0]), std::stod(f[1]) * deg, std::stod(f[2]) * deg});
  }
  EXPECT_EQ(static_cast<double>(traj.size()), doc.at("epochs").get<double>());
  const auto rec_fixes = ctxfuse::io::to_gnss_fixes(ctxfuse::io::read_rtklib_pos(dir / "gnss_1934_sf.pos"));
  std::vector<ctxfuse::pipelines::gins::OutageWindow> windows;
  for (const auto& w : doc.at("forward").at("outages")) windows.push_back({w.at("start").get<double>(), w.at("end").get<double>()});
  const auto again = ctxfuse::studies::outage_errors(traj, ctxfuse::studies::rtk_fixed_reference(rec_fixes), windows);
  // Stamps to the ms (the fixes' own resolution) and 1e-10 deg (1e-5 m): the same figure.
  EXPECT_NEAR(again.rms, smoothed, 1e-4);
  fs::remove_all(tmp);
}

TEST(CliRunGins, PlotsAgreeWithTheOutageScores) {
  CTXFUSE_REQUIRE_DATA(dir, "gnss-imu-drive");
  CTXFUSE_REQUIRE_GNUPLOT();
  namespace t = ctxfuse::test;
  const fs::path tmp = t::scratch_dir("run_gins_plot");
  const fs::path plots = tmp / "plots";
  const auto r = run("run gins --data \"" + dir.string() + "\"" + kDrive + " --outage 15:45:40 --gnss-rate 1 --constraints zupt,nhc --smooth --json \"" +
                     (tmp / "m.json").string() + "\" --plot \"" + plots.string() + "\"");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("plots in " + plots.string() + ": gins_trajectory.png gins_error_time.png gins_outage_error.png"), std::string::npos)
      << r.out;
  std::ifstream js(tmp / "m.json");
  const nlohmann::json doc = nlohmann::json::parse(js);

  const auto traj = t::expect_plot(plots, "gins_trajectory");
  for (const char* s : {"forward", "smoothed", "RTK reference (Q=1)"}) EXPECT_GT(traj.count(s) ? traj.at(s).size() : 0u, 100u) << s;
  // Every RTK-fixed epoch inside a window is marked, scored or not (before the alignment).
  const auto& fwd = doc.at("forward");
  ASSERT_TRUE(traj.count("reference inside outages"));
  EXPECT_EQ(traj.at("reference inside outages").size(), fwd.at("epochs").get<std::size_t>() + fwd.at("unscored_epochs").get<std::size_t>());

  // The errors marked inside outages are the ones the scores aggregate.
  const auto err = t::expect_plot(plots, "gins_error_time");
  const auto per = t::expect_plot(plots, "gins_outage_error");
  for (const std::string pass : {"forward", "smoothed"}) {
    const auto& sc = doc.at(pass);
    ASSERT_TRUE(err.count(pass + " error inside outages")) << pass;
    const auto& inside = err.at(pass + " error inside outages");
    EXPECT_EQ(inside.size(), sc.at("epochs").get<std::size_t>()) << pass;
    EXPECT_NEAR(t::rms_y(inside), sc.at("rms_m").get<double>(), t::six_digits(sc.at("rms_m"))) << pass;
    EXPECT_NEAR(t::max_y(inside), sc.at("max_m").get<double>(), t::six_digits(sc.at("max_m"))) << pass;
    const auto& all = err.at(pass + " horizontal error");
    const auto& sigma = err.at(pass + " 1-sigma horizontal");
    EXPECT_GT(all.size(), inside.size()) << pass;
    EXPECT_EQ(sigma.size(), all.size()) << pass;
    EXPECT_TRUE(std::all_of(sigma.begin(), sigma.end(), [](const auto& p) { return p.second > 0.0 && std::isfinite(p.second); }));
    // One row per outage with a scored epoch, at the window's number, with the JSON's figures.
    const auto& rms = per.at(pass + " RMS");
    const auto& max = per.at(pass + " max");
    std::size_t k = 0;
    for (std::size_t i = 0; i < sc.at("outages").size(); ++i) {
      const auto& o = sc.at("outages")[i];
      if (o.at("epochs").get<int>() == 0) continue;
      ASSERT_LT(k, rms.size()) << pass;
      EXPECT_EQ(rms[k].first, static_cast<double>(i + 1)) << pass;
      EXPECT_NEAR(rms[k].second, o.at("rms_m").get<double>(), t::six_digits(o.at("rms_m"))) << pass << " outage " << i + 1;
      EXPECT_NEAR(max[k].second, o.at("max_m").get<double>(), t::six_digits(o.at("max_m"))) << pass << " outage " << i + 1;
      ++k;
    }
    EXPECT_EQ(rms.size(), k) << pass;
    EXPECT_EQ(k, doc.at("outages_scored").get<std::size_t>()) << pass;
  }
  fs::remove_all(tmp);
}

}  // namespace run_gins_cli

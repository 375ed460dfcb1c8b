// CSV logs: a written drive reads back to the same values; malformed files give LogError
// naming file, line and field, and never crash.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "ctxfuse/sim/log_io.hpp"

namespace sim = ctxfuse::sim;

namespace {

const sim::Drive& small_drive() {
  static const sim::Drive d = [] {
    sim::DriveConfig c;
    c.route.duration_s = 200.0;
    c.route.indoor_laps = 1;
    return sim::simulate_drive(c);
  }();
  return d;
}

std::filesystem::path temp_dir(const std::string& name) {
  auto p = std::filesystem::temp_directory_path() / ("ctxfuse_sim_log_io_" + name + "_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  std::filesystem::remove_all(p);
  return p;
}

// Parses `text` as the named file and returns the error (or fails the test).
template <class Reader>
sim::LogError expect_error(Reader reader, const std::string& text) {
  std::istringstream in(text);
  try {
    (void)reader(in, "x.csv");
  } catch (const sim::LogError& e) {
    return e;
  }
  ADD_FAILURE() << "no LogError for:\n" << text;
  return sim::LogError("", 0, "", "");
}

auto imu_reader = [](std::istream& in, const std::string& f) { return sim::read_imu_csv(in, f); };
auto truth_reader = [](std::istream& in, const std::string& f) { return sim::read_truth_csv(in, f); };
auto uwb_reader = [](std::istream& in, const std::string& f) { return sim::read_uwb_csv(in, f); };

}  // namespace

TEST(SimLogIo, RoundTripKeepsEveryValueToTenDigits) {
  const auto& d = small_drive();
  const auto dir = temp_dir("roundtrip");
  sim::write_drive_logs(d, dir);
  const auto log = sim::read_drive_logs(dir);
  ASSERT_EQ(log.imu.size(), d.imu.size());
  ASSERT_EQ(log.gnss.size(), d.gnss.size());
  ASSERT_EQ(log.sats.size(), d.sats.size());
  ASSERT_EQ(log.uwb.size(), d.uwb.size());
  ASSERT_EQ(log.speed.size(), d.speed.size());
  ASSERT_EQ(log.mag.size(), d.mag.size());
  ASSERT_EQ(log.truth.size(), d.truth.size());
  auto close = [](double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(1.0, std::abs(b)); };
  for (std::size_t k = 0; k < d.imu.size(); k += 97) {
    EXPECT_TRUE(close(log.imu[k].t, d.imu[k].t));
    for (int i = 0; i < 3; ++i) {
      EXPECT_TRUE(close(log.imu[k].gyro[i], d.imu[k].gyro[i]));
      EXPECT_TRUE(close(log.imu[k].accel[i], d.imu[k].accel[i]));
    }
  }
  for (std::size_t k = 0; k < d.gnss.size(); ++k) {
    EXPECT_EQ(log.gnss[k].has_fix, d.gnss[k].has_fix);
    EXPECT_EQ(log.gnss[k].num_sats, d.gnss[k].num_sats);
    EXPECT_EQ(log.gnss[k].first_sat, d.gnss[k].first_sat);
    EXPECT_TRUE(close(log.gnss[k].pdop, d.gnss[k].pdop));
    for (int i = 0; i < 3; ++i) EXPECT_TRUE(close(log.gnss[k].position[i], d.gnss[k].position[i]));
  }
  for (std::size_t k = 0; k < d.uwb.size(); k += 7) {
    EXPECT_EQ(log.uwb[k].anchor_id, d.uwb[k].anchor_id);
    EXPECT_EQ(log.uwb[k].nlos, d.uwb[k].nlos);
    EXPECT_TRUE(close(log.uwb[k].range_m, d.uwb[k].range_m));
  }
  for (std::size_t k = 0; k < d.truth.size(); k += 101) {
    EXPECT_EQ(log.truth[k].region, d.truth[k].region);
    EXPECT_EQ(log.truth[k].is_static, d.truth[k].is_static);
    EXPECT_TRUE(close(log.truth[k].yaw, d.truth[k].yaw));
  }
  std::filesystem::remove_all(dir);
}

TEST(SimLogIo, MalformedRowsNameFileLineAndField) {
  const std::string h = std::string(sim::kImuHeader) + "\n";
  auto e = expect_error(imu_reader, h + "0,1,2,3,4,5,6\n0.01,1,2,3,4,5\n");
  EXPECT_EQ(e.file(), "x.csv");
  EXPECT_EQ(e.line(), 3u);
  EXPECT_NE(std::string(e.what()).find("expected 7 fields, found 6"), std::string::npos) << e.what();

  e = expect_error(imu_reader, h + "0,1,2,3,4,5,6\n0.01,1,abc,3,4,5,6\n");
  EXPECT_EQ(e.line(), 3u);
  EXPECT_EQ(e.field(), "gyro_y");

  e = expect_error(imu_reader, h + "0,1,2,3,nan,5,6\n");
  EXPECT_EQ(e.line(), 2u);
  EXPECT_EQ(e.field(), "accel_x");
  EXPECT_NE(std::string(e.what()).find("not finite"), std::string::npos) << e.what();

  e = expect_error(imu_reader, h + "0,1,2,3,inf,5,6\n");
  EXPECT_EQ(e.field(), "accel_x");

  e = expect_error(imu_reader, h + "0,1,2,3,1e300,5,6\n");
  EXPECT_NE(std::string(e.what()).find("absurd"), std::string::npos) << e.what();

  e = expect_error(imu_reader, h + "0.02,1,2,3,4,5,6\n0.01,1,2,3,4,5,6\n");
  EXPECT_EQ(e.line(), 3u);
  EXPECT_EQ(e.field(), "t");
  EXPECT_NE(std::string(e.what()).find("times must increase"), std::string::npos) << e.what();

  e = expect_error(imu_reader, "time,gx\n0,1\n");
  EXPECT_EQ(e.line(), 1u);
  EXPECT_NE(std::string(e.what()).find("header"), std::string::npos);

  e = expect_error(imu_reader, "");
  EXPECT_EQ(e.line(), 1u);

  // Labels out of range.
  std::string truth_row = "0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,9.8,0,3,0,0\n";
  e = expect_error(truth_reader, std::string(sim::kTruthHeader) + "\n" + truth_row);
  EXPECT_EQ(e.field(), "region");
  e = expect_error(uwb_reader, std::string(sim::kUwbHeader) + "\n0,1,0,0,0,5,-80,-82,2\n");
  EXPECT_EQ(e.field(), "nlos");
  // Several UWB rows share an epoch, but time may not go backwards.
  std::istringstream ok(std::string(sim::kUwbHeader) + "\n0,1,0,0,0,5,-80,-82,0\n0,2,0,0,0,5,-80,-82,1\r\n\n0.1,1,0,0,0,5,-80,-82,0\n");
  EXPECT_EQ(sim::read_uwb_csv(ok, "u.csv").size(), 3u);
  e = expect_error(uwb_reader, std::string(sim::kUwbHeader) + "\n0.1,1,0,0,0,5,-80,-82,0\n0,2,0,0,0,5,-80,-82,1\n");
  EXPECT_NE(std::string(e.what()).find("out of order"), std::string::npos) << e.what();
}

TEST(SimLogIo, DirectoryLevelErrorsNameTheFile) {
  const auto& d = small_drive();
  const auto dir = temp_dir("dir");
  sim::write_drive_logs(d, dir);
  std::filesystem::remove(dir / "mag.csv");
  try {
    (void)sim::read_drive_logs(dir);
    FAIL();
  } catch (const sim::LogError& e) {
    EXPECT_NE(e.file().find("mag.csv"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos);
  }
  sim::write_drive_logs(d, dir);
  // Drop one satellite row: gnss.csv and sats.csv disagree.
  {
    std::ifstream in(dir / "sats.csv");
    std::stringstream all;
    all << in.rdbuf();
    std::string text = all.str();
    const auto first_nl = text.find('\n');
    const auto second_nl = text.find('\n', first_nl + 1);
    text.erase(first_nl + 1, second_nl - first_nl);
    std::ofstream out(dir / "sats.csv");
    out << text;
  }
  try {
    (void)sim::read_drive_logs(dir);
    FAIL();
  } catch (const sim::LogError& e) {
    EXPECT_NE(e.file().find("sats.csv"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("satellites"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

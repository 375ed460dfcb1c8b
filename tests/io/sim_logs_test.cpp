// The simulator's CSV logs (sim/logs.hpp): a drive written and read back is bit for bit the
// drive (the sensor streams equal sim::sensor_log, the truth and labels the drive's own), and
// malformed files give io::ParseError naming file:line:column and the column, never a crash.
#include <gtest/gtest.h>

#include <ctxfuse/sim/logs.hpp>
#include <ctxfuse/sim/streams.hpp>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "temp_files.hpp"

namespace {

namespace io = ctxfuse::io;

namespace messages = ctxfuse::messages;
namespace sim = ctxfuse::sim;
namespace csv = ctxfuse::sim::csv;
using SimLogs = ctxfuse::test::TempFiles;

const sim::Drive& drive_seed_1() {
  static const sim::Drive d = [] {
    sim::DriveConfig c;
    c.seed = 1;
    c.route.duration_s = 200.0;
    c.route.indoor_laps = 1;
    return sim::simulate_drive(c);
  }();
  return d;
}

// Bit for bit: stricter than == (tells -0 from 0) and true for two identical NaNs (the DOPs
// of epochs with fewer than four satellites).
bool same(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }
template <class A, class B>
bool same(const Eigen::MatrixBase<A>& a, const Eigen::MatrixBase<B>& b) {
  for (Eigen::Index i = 0; i < a.rows(); ++i)
    for (Eigen::Index j = 0; j < a.cols(); ++j)
      if (!same(a(i, j), b(i, j))) return false;
  return true;
}
#define EXPECT_SAME(a, b, k) EXPECT_TRUE(same(a, b)) << #a << " of message " << (k) << ": " << (a) << " vs " << (b)

void expect_same(const messages::SensorLog& got, const messages::SensorLog& want) {
  ASSERT_EQ(got.imu.size(), want.imu.size());
  for (std::size_t k = 0; k < want.imu.size(); ++k) {
    EXPECT_SAME(got.imu[k].t, want.imu[k].t, k);
    EXPECT_SAME(got.imu[k].gyro, want.imu[k].gyro, k);
    EXPECT_SAME(got.imu[k].accel, want.imu[k].accel, k);
    EXPECT_EQ(got.imu[k].increments, want.imu[k].increments);
  }
  ASSERT_EQ(got.gnss.size(), want.gnss.size());
  for (std::size_t k = 0; k < want.gnss.size(); ++k) {
    const auto &g = got.gnss[k], &w = want.gnss[k];
    EXPECT_SAME(g.t, w.t, k);
    EXPECT_SAME(g.position, w.position, k);
    EXPECT_SAME(g.cov, w.cov, k);
    EXPECT_EQ(g.frame, w.frame);
    EXPECT_EQ(g.velocity.has_value(), w.velocity.has_value());
    EXPECT_SAME(g.velocity_cov, w.velocity_cov, k);
    EXPECT_EQ(g.quality, w.quality);
    EXPECT_EQ(g.satellites_used, w.satellites_used);
  }
  ASSERT_EQ(got.sat_epochs.size(), want.sat_epochs.size());
  for (std::size_t k = 0; k < want.sat_epochs.size(); ++k) {
    const auto &g = got.sat_epochs[k], &w = want.sat_epochs[k];
    EXPECT_SAME(g.t, w.t, k);
    EXPECT_SAME(g.pdop, w.pdop, k);
    EXPECT_SAME(g.hdop, w.hdop, k);
    ASSERT_EQ(g.sats.size(), w.sats.size()) << "epoch " << k;
    for (std::size_t i = 0; i < w.sats.size(); ++i) {
      EXPECT_EQ(g.sats[i].sat_id, w.sats[i].sat_id);
      EXPECT_SAME(g.sats[i].elevation_deg, w.sats[i].elevation_deg, k);
      EXPECT_SAME(g.sats[i].azimuth_deg, w.sats[i].azimuth_deg, k);
      EXPECT_SAME(g.sats[i].cn0_dbhz, w.sats[i].cn0_dbhz, k);
    }
  }
  ASSERT_EQ(got.uwb.size(), want.uwb.size());
  for (std::size_t k = 0; k < want.uwb.size(); ++k) {
    const auto &g = got.uwb[k], &w = want.uwb[k];
    EXPECT_SAME(g.t, w.t, k);
    EXPECT_EQ(g.anchor_id, w.anchor_id);
    EXPECT_SAME(g.anchor_position, w.anchor_position, k);
    EXPECT_SAME(g.range_m, w.range_m, k);
    EXPECT_SAME(g.rssi_dbm, w.rssi_dbm, k);
    EXPECT_SAME(g.rssi_first_path_dbm, w.rssi_first_path_dbm, k);
  }
  ASSERT_EQ(got.speed.size(), want.speed.size());
  for (std::size_t k = 0; k < want.speed.size(); ++k) {
    EXPECT_SAME(got.speed[k].t, want.speed[k].t, k);
    EXPECT_SAME(got.speed[k].speed_mps, want.speed[k].speed_mps, k);
  }
  ASSERT_EQ(got.mag.size(), want.mag.size());
  for (std::size_t k = 0; k < want.mag.size(); ++k) {
    EXPECT_SAME(got.mag[k].t, want.mag[k].t, k);
    EXPECT_SAME(got.mag[k].field_ut, want.mag[k].field_ut, k);
  }
}

void expect_same(const std::vector<sim::TruthSample>& got, const std::vector<sim::TruthSample>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t k = 0; k < want.size(); ++k) {
    const auto &g = got[k], &w = want[k];
    EXPECT_SAME(g.t, w.t, k);
    EXPECT_SAME(g.position, w.position, k);
    EXPECT_SAME(g.velocity, w.velocity, k);
    EXPECT_SAME(g.roll, w.roll, k);
    EXPECT_SAME(g.pitch, w.pitch, k);
    EXPECT_SAME(g.yaw, w.yaw, k);
    EXPECT_SAME(g.angular_rate, w.angular_rate, k);
    EXPECT_SAME(g.specific_force, w.specific_force, k);
    EXPECT_SAME(g.speed, w.speed, k);
    EXPECT_EQ(g.region, w.region);
    EXPECT_EQ(g.scene, w.scene);
    EXPECT_EQ(g.is_static, w.is_static);
  }
}

// Reads `text` as a file named `name` with `reader` and returns the error (or fails the test).
template <class Reader>
io::ParseError expect_error(const std::filesystem::path& dir, Reader reader, const std::string& name, const std::string& text) {
  const auto path = dir / name;
  std::ofstream(path, std::ios::binary) << text;
  try {
    (void)reader(path);
  } catch (const io::ParseError& e) {
    EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    return e;
  }
  ADD_FAILURE() << "no ParseError for:\n" << text;
  return io::ParseError("", 0, 0, "", "");
}
#define WHAT_HAS(e, s) EXPECT_NE(std::string((e).what()).find(s), std::string::npos) << (e).what()

// The error of each directory reader (row by row, and read_sim_logs): they check alike.
std::vector<io::ParseError> errors_of_both_readers(const std::filesystem::path& dir) {
  std::vector<io::ParseError> out;
  for (const bool rows : {true, false}) {
    try {
      if (rows)
        (void)sim::csv::read_drive_logs(dir);
      else
        (void)sim::read_sim_logs(dir);
      ADD_FAILURE() << (rows ? "read_drive_logs" : "read_sim_logs") << " found no error";
    } catch (const io::ParseError& e) {
      out.push_back(e);
    }
  }
  return out;
}
// The former name of the error, for callers of sim/log_io.hpp.
static_assert(std::is_same_v<io::ParseError, io::ParseError>);

auto imu_reader = [](const std::filesystem::path& p) { return csv::read_imu(p); };

}  // namespace

// With 10 significant digits (the former writer) none of this would hold.
TEST_F(SimLogs, DriveWrittenAndReadBackIsBitForBitTheDrive) {
  const auto& d = drive_seed_1();
  sim::write_drive_logs(d, dir_);
  const auto logs = sim::read_sim_logs(dir_);
  const auto want = sim::sensor_log(d);
  ASSERT_GT(want.uwb.size(), 100u);
  ASSERT_GT(want.gnss.size(), 10u);
  expect_same(logs.sensors, want);
  expect_same(logs.truth.truth, d.truth);

  // Labels apart: LOS per satellite, NLOS per range, nothing the logs do not hold.
  ASSERT_EQ(logs.truth.sats.size(), d.sats.size());
  for (std::size_t k = 0; k < d.sats.size(); ++k) {
    EXPECT_SAME(logs.truth.sats[k].t, d.sats[k].t, k);
    EXPECT_EQ(logs.truth.sats[k].sat_id, d.sats[k].sat_id);
    EXPECT_EQ(logs.truth.sats[k].line_of_sight, d.sats[k].line_of_sight);
  }
  ASSERT_EQ(logs.truth.uwb.size(), d.uwb.size());
  std::size_t nlos = 0;
  for (std::size_t k = 0; k < d.uwb.size(); ++k) {
    EXPECT_SAME(logs.truth.uwb[k].t, d.uwb[k].t, k);
    EXPECT_EQ(logs.truth.uwb[k].anchor_id, d.uwb[k].anchor_id);
    EXPECT_EQ(logs.truth.uwb[k].nlos, d.uwb[k].nlos);
    EXPECT_TRUE(std::isnan(logs.truth.uwb[k].true_range_m));  // not in the logs
    nlos += d.uwb[k].nlos ? 1 : 0;
  }
  EXPECT_GT(nlos, 0u);
  EXPECT_TRUE(logs.truth.fixes.empty());

  // The former reader's view, row by row, is exact too.
  const auto rows = sim::csv::read_drive_logs(dir_);
  ASSERT_EQ(rows.gnss.size(), d.gnss.size());
  for (std::size_t k = 0; k < d.gnss.size(); ++k) {
    EXPECT_EQ(rows.gnss[k].has_fix, d.gnss[k].has_fix);
    EXPECT_EQ(rows.gnss[k].num_sats, d.gnss[k].num_sats);
    EXPECT_EQ(rows.gnss[k].first_sat, d.gnss[k].first_sat);
    EXPECT_SAME(rows.gnss[k].pdop, d.gnss[k].pdop, k);
    EXPECT_SAME(rows.gnss[k].mean_cn0_dbhz, d.gnss[k].mean_cn0_dbhz, k);
  }
  ASSERT_EQ(rows.uwb.size(), d.uwb.size());
  for (std::size_t k = 0; k < d.uwb.size(); ++k) EXPECT_EQ(rows.uwb[k].nlos, d.uwb[k].nlos);
}

TEST_F(SimLogs, NumbersAreWrittenInTheirShortestRoundTripForm) {
  sim::Drive d;
  const double third = 1.0 / 3.0, above_one = std::nextafter(1.0, 2.0);
  d.imu.push_back({0.1, Eigen::Vector3d(third, -0.0, 1e-300), Eigen::Vector3d(above_one, 123456789.125, -9.81)});
  d.imu.push_back({0.2, Eigen::Vector3d(0.0, 2.0 / 3.0, 1e11), Eigen::Vector3d::Zero()});
  std::ostringstream os;
  csv::write_log(os, d, "imu.csv");
  EXPECT_EQ(os.str(), std::string(csv::kImuHeader) +
                          "\n0.1,0.3333333333333333,-0,1e-300,1.0000000000000002,123456789.125,-9.81"
                          "\n0.2,0,0.6666666666666666,1e+11,0,0,0\n");
  sim::write_drive_logs(d, dir_);
  const auto back = sim::read_sim_logs(dir_);
  expect_same(back.sensors, sim::sensor_log(d));
  EXPECT_TRUE(std::signbit(back.sensors.imu[0].gyro.y()));
}

TEST_F(SimLogs, MalformedRowsNameFileLineAndColumn) {
  const std::string h = std::string(csv::kImuHeader) + "\n";
  auto e = expect_error(dir_, imu_reader, "x.csv", h + "0,1,2,3,4,5,6\n0.01,1,2,3,4,5\n");
  EXPECT_NE(e.file().find("x.csv"), std::string::npos);
  EXPECT_EQ(e.line(), 3u);
  EXPECT_EQ(e.column(), 0u);  // the row as a whole
  WHAT_HAS(e, "x.csv:3: 6 fields, expected 7");

  e = expect_error(dir_, imu_reader, "x.csv", h + "0,1,2,3,4,5,6\n0.01,1,abc,3,4,5,6\n");
  EXPECT_EQ(e.line(), 3u);
  EXPECT_EQ(e.column(), 3u);
  EXPECT_EQ(e.column_name(), "gyro_y");
  WHAT_HAS(e, "x.csv:3:3: column 'gyro_y': 'abc' is not a number");

  e = expect_error(dir_, imu_reader, "x.csv", h + "0,1,2,3,nan,5,6\n");
  EXPECT_EQ(e.line(), 2u);
  EXPECT_EQ(e.column_name(), "accel_x");
  WHAT_HAS(e, "x.csv:2:5: column 'accel_x': 'nan' is not finite");
  e = expect_error(dir_, imu_reader, "x.csv", h + "0,1,2,3,inf,5,6\n");
  EXPECT_EQ(e.column_name(), "accel_x");
  e = expect_error(dir_, imu_reader, "x.csv", h + "0,1,2,3,1e300,5,6\n");
  WHAT_HAS(e, "x.csv:2:5: column 'accel_x': '1e300' is beyond the magnitude");
  e = expect_error(dir_, imu_reader, "x.csv", h + "0,1,2,3,2e12,5,6\n");  // the 1e12 bound of these logs
  WHAT_HAS(e, "beyond the magnitude");

  e = expect_error(dir_, imu_reader, "x.csv", h + "0.02,1,2,3,4,5,6\n0.01,1,2,3,4,5,6\n");
  EXPECT_EQ(e.line(), 3u);
  EXPECT_EQ(e.column_name(), "t");
  WHAT_HAS(e, "x.csv:3:1: column 't': time 0.01 is not after the previous row's 0.02 (times must increase)");
  e = expect_error(dir_, imu_reader, "x.csv", h + "0.02,1,2,3,4,5,6\n0.02,1,2,3,4,5,6\n");
  WHAT_HAS(e, "times must increase");

  e = expect_error(dir_, imu_reader, "x.csv", "time,gx\n0,1\n");
  EXPECT_EQ(e.line(), 1u);
  WHAT_HAS(e, "x.csv:1: header is 'time,gx', expected 't,gyro_x");
  e = expect_error(dir_, imu_reader, "x.csv", "");
  EXPECT_EQ(e.line(), 1u);
  WHAT_HAS(e, "empty file");

  // Labels and values out of range.
  e = expect_error(dir_, csv::read_truth, "truth.csv",
                   std::string(csv::kTruthHeader) + "\n0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,9.8,0,3,0,0\n");
  EXPECT_EQ(e.column_name(), "region");
  WHAT_HAS(e, "truth.csv:2:18: column 'region': '3' is outside the allowed range [0, 2]");
  const std::string uh = std::string(csv::kUwbHeader) + "\n";
  e = expect_error(dir_, csv::read_uwb, "uwb.csv", uh + "0,1,0,0,0,5,-80,-82,2\n");
  EXPECT_EQ(e.column_name(), "nlos");
  EXPECT_EQ(e.column(), 9u);
  e = expect_error(dir_, csv::read_uwb, "uwb.csv", uh + "0,1,0,0,0,2e4,-80,-82,0\n");
  WHAT_HAS(e, "uwb.csv:2:6: column 'range': range must be within [-10, 10000] m (is 20000)");
  const std::string sh = std::string(csv::kSatsHeader) + "\n";
  WHAT_HAS(expect_error(dir_, csv::read_sats, "sats.csv", sh + "0,101,95,10,40,1\n"), "sats.csv:2:3: column 'elevation_deg'");
  WHAT_HAS(expect_error(dir_, csv::read_sats, "sats.csv", sh + "0,101,45,360,40,1\n"), "sats.csv:2:4: column 'azimuth_deg': azimuth must be within [0, 360)");
  WHAT_HAS(expect_error(dir_, csv::read_sats, "sats.csv", sh + "0,101,45,10,80,1\n"), "sats.csv:2:5: column 'cn0_dbhz'");
  WHAT_HAS(expect_error(dir_, csv::read_sats, "sats.csv", sh + "0,1000,45,10,40,1\n"), "sats.csv:2:2: column 'sat_id'");
  const std::string gh = std::string(csv::kGnssHeader) + "\n";
  WHAT_HAS(expect_error(dir_, csv::read_gnss, "gnss.csv", gh + "0,1,1,2,3,0,2,6,1.5,1,40\n"), "gnss.csv:2:6: column 'std_h': a fix needs positive std_h and std_v");
  WHAT_HAS(expect_error(dir_, csv::read_gnss, "gnss.csv", gh + "0,1,1,2,3,1,2,3,1.5,1,40\n"), "gnss.csv:2:8: column 'num_sats': a fix needs at least 4");
  WHAT_HAS(expect_error(dir_, csv::read_gnss, "gnss.csv", gh + "0,1,1,2,3,1,2,6,1.5,1,40,7\n"), "gnss.csv:2: 12 fields, expected 11");
  WHAT_HAS(expect_error(dir_, csv::read_speed, "speed.csv", "t,speed\n0,250\n"), "speed.csv:2:2: column 'speed': speed must be within [-100, 100]");
  WHAT_HAS(expect_error(dir_, csv::read_mag, "mag.csv", "t,mag_x,mag_y,mag_z\n0,2e4,0,0\n"), "mag.csv:2:2: column 'mag_x': field magnitude above 10000 uT");
  try {
    (void)csv::read_imu(dir_ / "absent.csv");
    ADD_FAILURE() << "no error for a missing file";
  } catch (const io::ParseError& err) {
    WHAT_HAS(err, "absent.csv: cannot open file");
  }

  // Several UWB rows share an epoch (CRLF and blank lines accepted), but time may not go back.
  std::ofstream(dir_ / "ok.csv", std::ios::binary) << uh << "0,1,0,0,0,5,-80,-82,0\n0,2,0,0,0,5,-80,-82,1\r\n\n0.1,1,0,0,0,5,-80,-82,0\n";
  EXPECT_EQ(csv::read_uwb(dir_ / "ok.csv").size(), 3u);
  e = expect_error(dir_, csv::read_uwb, "uwb.csv", uh + "0.1,1,0,0,0,5,-80,-82,0\n0,2,0,0,0,5,-80,-82,1\n");
  WHAT_HAS(e, "uwb.csv:3:1: column 't': time 0 is not after the previous row's 0.1 (out of order)");
}

TEST_F(SimLogs, DirectoryLevelErrorsNameTheFile) {
  const auto& d = drive_seed_1();
  sim::write_drive_logs(d, dir_);
  std::filesystem::remove(dir_ / "mag.csv");
  for (const auto& e : errors_of_both_readers(dir_)) {
    EXPECT_NE(e.file().find("mag.csv"), std::string::npos);
    WHAT_HAS(e, "cannot open");
  }
  sim::write_drive_logs(d, dir_);
  // Drop the first satellite row: gnss.csv and sats.csv disagree.
  auto rewrite_sats = [&](auto edit) {
    std::ifstream in(dir_ / "sats.csv");
    std::stringstream all;
    all << in.rdbuf();
    std::string text = all.str();
    edit(text);
    std::ofstream(dir_ / "sats.csv", std::ios::binary) << text;
  };
  rewrite_sats([](std::string& text) {
    const auto first_nl = text.find('\n');
    text.erase(first_nl + 1, text.find('\n', first_nl + 1) - first_nl);
  });
  for (const auto& e : errors_of_both_readers(dir_)) {
    EXPECT_NE(e.file().find("sats.csv"), std::string::npos);
    EXPECT_EQ(e.line(), 2u);
    WHAT_HAS(e, "satellites");
  }
  // A satellite row after the last epoch.
  sim::write_drive_logs(d, dir_);
  rewrite_sats([](std::string& text) { text += "12345.5,101,45,10,40,1\n"; });
  for (const auto& e : errors_of_both_readers(dir_)) WHAT_HAS(e, "time 12345.5 is not an epoch of gnss.csv");
}

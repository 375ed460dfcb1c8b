// The Hanyang UWB reader (an anchor file, trajectory.csv) and the simulator's IMU log, each
// cut at every byte. Asserted: no crash, any error is io::ParseError naming the file, and the
// whole lines before the cut come back exactly as from the uncut file. What these readers do
// with the cut line itself is classified: skipped, refused, or read as a different value (a
// number cut short still parses). The last is a distortion; the *NeverDistorted tests assert
// it never happens: these readers skip a last line without its newline, as the readers of
// partial_files_test.cpp do.
#include <gtest/gtest.h>

#include <ctxfuse/io/hanyang_uwb.hpp>
#include <ctxfuse/sim/logs.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "temp_files.hpp"

namespace {

using namespace ctxfuse::io;
using CutReaders = ctxfuse::test::TempFiles;

void write_text(const std::filesystem::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

using ctxfuse::test::whole_lines;

/// One reader's records as rows of doubles, so that one routine compares them all.
using Rows = std::vector<std::vector<double>>;

struct Outcomes {
  std::size_t skipped = 0, refused = 0, distorted = 0;
};

/// Cuts `text` at every byte, reads it with `read` and checks the records of whole lines
/// against `full` exactly. `header_lines` lines precede the records.
Outcomes cut_everywhere(const std::string& text, std::size_t header_lines, const std::function<Rows(const std::string&)>& read,
                        const std::string& file_name) {
  const Rows full = read(text);
  Outcomes o;
  for (std::size_t cut = 0; cut <= text.size(); ++cut) {
    SCOPED_TRACE(file_name + " cut at byte " + std::to_string(cut));
    const std::size_t lines = whole_lines(text, cut);
    const std::size_t whole = lines > header_lines ? lines - header_lines : 0;
    const bool mid_record = lines >= header_lines && cut > 0 && text[cut - 1] != '\n';
    Rows got;
    try {
      got = read(text.substr(0, cut));
    } catch (const ParseError& e) {
      EXPECT_NE(std::string(e.what()).find(file_name), std::string::npos) << e.what();
      if (lines >= header_lines) {
        EXPECT_TRUE(mid_record) << "whole records refused: " << e.what();
      }
      ++o.refused;
      continue;
    }
    if (got.size() < whole) {
      ADD_FAILURE() << got.size() << " records for " << whole << " whole lines";
      continue;
    }
    for (std::size_t i = 0; i < whole; ++i) EXPECT_EQ(got[i], full[i]) << "record " << i;
    if (got.size() == whole) {
      o.skipped += mid_record;
    } else if (got.size() == whole + 1 && mid_record) {
      o.distorted += got[whole] != full[whole];  // the cut line read as a record
    } else {
      ADD_FAILURE() << got.size() << " records for " << whole << " whole lines";
    }
  }
  return o;
}

const std::string kAnchor =
    "%time,field.stamp,field.id,field.x,field.y,field.z,field.distanceFromTag,field.rssi,field.rssi_fp\n"
    "1734501485317590607,1,3,2.5775,0.87,1.97,7.5,-79.71,-80.75\n"
    "1734501485417273454,1,3,2.5775,0.87,1.97,7.25,-inf,-80.5\n"
    "1734501485517273454,1,3,2.5775,0.87,1.97,7.125,-78.25,-81.625\n"
    "1734501485617273454,1,3,2.5775,0.87,1.97,7.0625,-79.5,-82.375\n";

Rows hanyang_rows(const std::filesystem::path& dir, const std::string& text) {
  write_text(dir / "A3.csv", text);
  Rows rows;
  for (const auto& r : read_hanyang_uwb(dir).ranges)
    rows.push_back({static_cast<double>(r.t_ns), r.range.anchor_position.x(), r.range.range_m,
                    std::isnan(r.range.rssi_dbm) ? -1e9 : r.range.rssi_dbm, r.range.rssi_first_path_dbm});
  return rows;
}

TEST_F(CutReaders, HanyangAnchorFileWholeLinesExact) {
  const auto o = cut_everywhere(kAnchor, 1, [&](const std::string& t) { return hanyang_rows(dir_, t); }, "A3.csv");
  std::cout << "A3.csv cuts: " << o.skipped << " skipped, " << o.refused << " refused, " << o.distorted << " distorted\n";
}

TEST_F(CutReaders, HanyangAnchorFileCutLineNeverDistorted) {
  EXPECT_EQ(cut_everywhere(kAnchor, 1, [&](const std::string& t) { return hanyang_rows(dir_, t); }, "A3.csv").distorted, 0u);
}

const std::string kTrajectory =
    "timestamp,x,y,z,heading_degrees\n"
    "1.7345014855003267e+18,-2.5775,-4.25,0.0,0.0\n"
    "1.7345014856253268e+18,-2.577500424675722,-4.249603603939604,0.011,370.5\n"
    "1.7345014857503268e+18,-2.5625,-4.125,0.0125,371.25\n";

Rows trajectory_rows(const std::filesystem::path& dir, const std::string& text) {
  write_text(dir / "trajectory.csv", text);
  Rows rows;
  for (const auto& p : read_hanyang_reference(dir)) rows.push_back({p.t, p.position.x(), p.position.y(), p.position.z(), p.heading_deg});
  return rows;
}

TEST_F(CutReaders, HanyangTrajectoryWholeLinesExact) {
  const auto o = cut_everywhere(kTrajectory, 1, [&](const std::string& t) { return trajectory_rows(dir_, t); }, "trajectory.csv");
  std::cout << "trajectory.csv cuts: " << o.skipped << " skipped, " << o.refused << " refused, " << o.distorted << " distorted\n";
}

TEST_F(CutReaders, HanyangTrajectoryCutLineNeverDistorted) {
  EXPECT_EQ(cut_everywhere(kTrajectory, 1, [&](const std::string& t) { return trajectory_rows(dir_, t); }, "trajectory.csv").distorted,
            0u);
}

const std::string kSimImu = std::string(ctxfuse::sim::csv::kImuHeader) +
                            "\n"
                            "0.01,0.001,-0.002,0.0125,0.125,-0.25,9.80665\n"
                            "0.02,0.0015,-0.0025,0.0175,0.1875,-0.3125,9.8125\n"
                            "0.03,0.002,-0.003,0.025,0.25,-0.375,9.825\n";

Rows sim_imu_rows(const std::filesystem::path& dir, const std::string& text) {
  write_text(dir / "imu.csv", text);
  Rows rows;
  for (const auto& s : ctxfuse::sim::csv::read_imu(dir / "imu.csv"))
    rows.push_back({s.t, s.gyro.x(), s.gyro.y(), s.gyro.z(), s.accel.x(), s.accel.y(), s.accel.z()});
  return rows;
}

TEST_F(CutReaders, SimImuLogWholeLinesExact) {
  const auto o = cut_everywhere(kSimImu, 1, [&](const std::string& t) { return sim_imu_rows(dir_, t); }, "imu.csv");
  std::cout << "sim imu.csv cuts: " << o.skipped << " skipped, " << o.refused << " refused, " << o.distorted << " distorted\n";
}

TEST_F(CutReaders, SimImuLogCutLineNeverDistorted) {
  EXPECT_EQ(cut_everywhere(kSimImu, 1, [&](const std::string& t) { return sim_imu_rows(dir_, t); }, "imu.csv").distorted, 0u);
}

}  // namespace

// IMU csv + RTKLIB time-tag reader on files written here: partial first/last lines, the tick
// to GPS time mapping, SI conversion, and every malformed csv and tag file.
#include <gtest/gtest.h>

#include <ctxfuse/io/imu_tag.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "temp_files.hpp"

namespace {

using namespace ctxfuse::io;
using Imu = ctxfuse::test::TempFiles;

std::string le32(std::uint32_t v) {
  std::string s(4, '\0');
  for (int i = 0; i < 4; ++i) s[static_cast<std::size_t>(i)] = static_cast<char>((v >> (8 * i)) & 0xff);
  return s;
}

std::string tag_bytes(std::uint32_t start, double fraction, const std::vector<std::uint32_t>& ticks,
                      const std::string& magic = "TIMETAG RTKLIB demo5") {
  std::string s = magic;
  s.resize(60, '\0');
  s += le32(7);  // the flag word: must not matter
  s += le32(start);
  std::uint64_t bits = 0;
  std::memcpy(&bits, &fraction, 8);
  s += le32(static_cast<std::uint32_t>(bits)) + le32(static_cast<std::uint32_t>(bits >> 32));
  std::uint32_t offset = 0;
  for (const auto t : ticks) s += le32(t) + le32(offset += 40);
  return s;
}

std::string row(int tick, const std::string& first = "0.1") {
  return first + ",0.2,1.0,10.0,-20.0,30.0," + std::to_string(tick) + "\n";
}

TEST_F(Imu, SkipsPartialEndsAndMapsTicksToGpsTime) {
  const auto csv = write("imu.csv", "0.027,1.013,-0.671,3.082\n" + row(1000, "0.5") + row(1010) + row(1020) +
                                        row(1040) + "0.1,0.2,1.0,10.0,-20.0,30.0,10");
  const auto tag_path = write("imu.csv.tag", tag_bytes(1752003261u, 0.5, {15, 30, 41}));
  const auto log = read_imu_csv(csv);
  ASSERT_EQ(log.records.size(), 4u);
  EXPECT_TRUE(log.skipped_first_line);
  EXPECT_TRUE(log.skipped_last_line);  // no newline: "10" may be a cut "1050"
  EXPECT_EQ(log.skipped_lines(), 2u);
  EXPECT_EQ(log.records[0].accel_g, Eigen::Vector3d(0.5, 0.2, 1.0));
  EXPECT_EQ(log.records[0].gyro_dps, Eigen::Vector3d(10.0, -20.0, 30.0));
  EXPECT_EQ(log.records[0].tick_ms, 1000);
  EXPECT_EQ(log.records[0].line, 2u);
  EXPECT_EQ(log.records[3].tick_ms, 1040);

  const auto tag = read_time_tag(tag_path);
  EXPECT_EQ(tag.start_s, 1752003261u);
  EXPECT_EQ(tag.start_fraction_s, 0.5);
  EXPECT_EQ(tag.header_word, 7u);
  ASSERT_EQ(tag.records.size(), 3u);
  EXPECT_EQ(tag.records[2].tick_ms, 41u);
  EXPECT_EQ(tag.records[2].byte_offset, 120u);

  // 40 IMU ticks span 41 PC milliseconds: each tick is 1.025 ms of GPS time.
  const ImuClock clock(log, tag);
  EXPECT_DOUBLE_EQ(clock.seconds_per_tick(), 0.041 / 40.0);
  const auto plain = to_imu_samples(log, tag);
  ASSERT_EQ(plain.size(), 4u);
  EXPECT_EQ(plain[0].t, 1752003261.5);
  EXPECT_NEAR(plain[1].t - 1752003261.5, 0.01025, 1e-6);
  EXPECT_NEAR(plain[3].t - 1752003261.5, 0.041, 1e-6);
  EXPECT_FALSE(plain[0].increments);
  EXPECT_EQ(plain[0].accel, Eigen::Vector3d(0.5, 0.2, 1.0) * 9.80665);
  EXPECT_EQ(plain[0].gyro, Eigen::Vector3d(10.0, -20.0, 30.0) * (std::numbers::pi / 180.0));

  ImuConversion delayed;
  delayed.delay_s = -0.125;
  const auto late = to_imu_samples(log, tag, delayed);
  for (std::size_t i = 0; i < late.size(); ++i) EXPECT_NEAR(late[i].t, plain[i].t - 0.125, 1e-6);
}

TEST_F(Imu, WholeEndsAreKept) {
  const auto log = read_imu_csv(write("imu.csv", row(5) + row(6) + row(7) + "\n"));
  ASSERT_EQ(log.records.size(), 3u);
  EXPECT_EQ(log.skipped_lines(), 0u);
  // A last line with its newline but not a whole record is still a cut line.
  const auto cut = read_imu_csv(write("cut.csv", row(5) + row(6) + "0.1,0.2\n"));
  EXPECT_EQ(cut.records.size(), 2u);
  EXPECT_TRUE(cut.skipped_last_line);
  EXPECT_FALSE(cut.skipped_first_line);
}

TEST_F(Imu, MalformedCsvLinesNameFileLineColumn) {
  const std::string head = row(1) + row(2);  // bad line is line 3, followed by a good one
  const std::string tail = row(10);
  EXPECT_PARSE_ERROR(read_imu_csv(write("count.csv", head + "0.1,0.2,1.0,10.0,-20.0,5\n" + tail)), "count.csv:3: ",
                     "6 fields, expected 7");
  EXPECT_PARSE_ERROR(read_imu_csv(write("word.csv", head + "0.1,abc,1.0,10.0,-20.0,30.0,3\n" + tail)), "word.csv:3:2: ",
                     "'abc' is not a number");
  EXPECT_PARSE_ERROR(read_imu_csv(write("nan.csv", head + "0.1,0.2,1.0,nan,-20.0,30.0,3\n" + tail)), "nan.csv:3:4: ",
                     "'nan' is not finite");
  EXPECT_PARSE_ERROR(read_imu_csv(write("big.csv", head + row(3, "500") + tail)), "big.csv:3:1: ", "outside [-100, 100]");
  EXPECT_PARSE_ERROR(read_imu_csv(write("tick.csv", head + "0.1,0.2,1.0,10.0,-20.0,30.0,3.5\n" + tail)), "tick.csv:3:7: ",
                     "'3.5' has characters after the number");
  EXPECT_PARSE_ERROR(read_imu_csv(write("neg.csv", head + row(-3) + tail)), "neg.csv:3:7: ", "outside the allowed range");
  EXPECT_PARSE_ERROR(read_imu_csv(write("back.csv", head + row(2) + tail)), "back.csv:3:7: ",
                     "tick 2 is not after the previous record's 2 (line 2)");
  EXPECT_PARSE_ERROR(read_imu_csv(dir_ / "absent.csv"), "absent.csv: ", "cannot open file");
}

TEST_F(Imu, MalformedTagFilesAreRefused) {
  EXPECT_PARSE_ERROR(read_time_tag(write("short.tag", tag_bytes(1, 0.0, {}).substr(0, 40))), "short.tag: ",
                     "file too short: 40 bytes");
  EXPECT_PARSE_ERROR(read_time_tag(write("magic.tag", tag_bytes(1, 0.0, {5}, "TIMETAG RTKLIX demo5"))), "magic.tag: ",
                     "header does not start with \"TIMETAG RTKLIB\"");
  EXPECT_PARSE_ERROR(read_time_tag(write("cut1.tag", tag_bytes(1, 0.0, {5}).substr(0, 76 + 3))), "cut1.tag: ",
                     "no whole tick record after the header (3 of 8 bytes)");
  EXPECT_PARSE_ERROR(read_time_tag(write("none.tag", tag_bytes(1, 0.0, {}))), "none.tag: ", "no tick records");
  EXPECT_PARSE_ERROR(read_time_tag(write("frac.tag", tag_bytes(1, 1.5, {5}))), "frac.tag: ", "outside [0, 1)");
  EXPECT_PARSE_ERROR(read_time_tag(write("back.tag", tag_bytes(1, 0.0, {5, 9, 8}))), "back.tag: ",
                     "record at byte 92 goes backwards (tick 8");
  EXPECT_PARSE_ERROR(read_time_tag(dir_ / "absent.tag"), "absent.tag: ", "cannot open file");

  const auto log = read_imu_csv(write("one.csv", row(1) + row(2)));
  EXPECT_PARSE_ERROR(ImuClock(log, read_time_tag(write("zero.tag", tag_bytes(1, 0.0, {0})))), "zero.tag: ",
                     "last tick record is 0 ms");
  const auto single = read_imu_csv(write("single.csv", row(1)));
  EXPECT_PARSE_ERROR(to_imu_samples(single, read_time_tag(write("ok.tag", tag_bytes(1, 0.0, {5})))), "single.csv: ",
                     "fewer than 2 records");
}

}  // namespace

// IMU csv + time tag: files cut short (the csv, the tag, either mid-record), the tick mapping
// chosen for each (ImuTimeMapping), and the writer's round trip with an IMU clock that runs
// 50 ppm fast and stamps at irregular 6-9 ms steps.
#include <gtest/gtest.h>

#include <ctxfuse/io/imu_tag.hpp>

#include <cmath>
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "temp_files.hpp"

namespace {

using namespace ctxfuse::io;
using namespace ctxfuse::messages;
using ImuPartial = ctxfuse::test::TempFiles;
using Method = ImuTimeMapping::Method;

using ctxfuse::test::slurp;

// A simulated logging: true times at irregular 6-9 ms steps from t0, the IMU's tick running
// `rate_ppm` fast with up to +-0.4 ms of stamp jitter, each sample reaching the PC at its true
// time. Values are arbitrary but distinct per sample.
struct Simulated {
  std::vector<ImuSample> samples;
  std::vector<std::int64_t> ticks;
  double t0 = 1752003261.25;
};

Simulated simulate(std::size_t n, double rate_ppm, unsigned seed) {
  Simulated s;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> step(0.006, 0.009), jitter(-0.4, 0.4), value(-1.0, 1.0);
  double t = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    ImuSample x;
    x.t = s.t0 + t;
    x.gyro = Eigen::Vector3d(value(rng), value(rng), value(rng)) * 2.0;
    x.accel = Eigen::Vector3d(value(rng), value(rng), value(rng)) * 12.0;
    s.samples.push_back(x);
    s.ticks.push_back(123456 + std::llround(t * (1.0 + rate_ppm * 1e-6) * 1000.0 + jitter(rng)));
    t += step(rng);
  }
  return s;
}

TEST_F(ImuPartial, RoundTripRecoversA50PpmClockAndIrregularSteps) {
  const auto sim = simulate(20000, 50.0, 1);  // about 150 s at about 133 Hz
  const auto csv = dir_ / "imu.csv";
  write_imu_csv_and_tag(csv, sim.samples, sim.ticks, sim.t0);
  const auto log = read_imu_csv(csv);
  ASSERT_EQ(log.records.size(), sim.samples.size());
  EXPECT_EQ(log.skipped_lines(), 0u);
  ImuTimeMapping m;
  const auto back = to_imu_samples(log, read_time_tag(csv.string() + ".tag"), {}, &m);
  EXPECT_EQ(m.method, Method::scaled) << m.why;
  // The fit is the inverse of the clock's rate, to within the ms rounding of both spans.
  EXPECT_NEAR(m.scale_ppm, -50.0, 10.0) << m.why;  // 1.4 ms of rounding and jitter over 150 s
  double worst = 0.0;
  for (std::size_t i = 0; i < back.size(); ++i) {
    ASSERT_EQ(log.records[i].tick_ms, sim.ticks[i]);
    // The shortest text reads back to the written double; deg <-> rad and g <-> m/s^2 cost
    // at most a few ulps.
    EXPECT_NEAR((back[i].gyro - sim.samples[i].gyro).norm(), 0.0, 1e-14);
    EXPECT_NEAR((back[i].accel - sim.samples[i].accel).norm(), 0.0, 1e-13);
    worst = std::max(worst, std::abs(back[i].t - sim.samples[i].t));
  }
  // Tick rounding (0.5 ms), jitter (0.4 ms) and the tag's ms rounding; without the rate
  // correction the last samples would be 50 ppm * 150 s = 7.5 ms late.
  EXPECT_LT(worst, 1.5e-3);
}

TEST_F(ImuPartial, WriterKeepsFixedDecimalsCrlfAndChunkedTags) {
  const auto sim = simulate(400, -30.0, 2);
  const auto csv = dir_ / "imu.csv";
  ImuCsvWriteOptions opt;
  opt.decimals = 3;
  opt.line_ending = "\r\n";
  opt.lines_per_tag_record = 7;
  write_imu_csv_and_tag(csv, sim.samples, sim.ticks, sim.t0, opt);
  const std::string text = slurp(csv);
  const auto log = read_imu_csv(csv);
  ASSERT_EQ(log.records.size(), 400u);
  EXPECT_EQ(log.bytes, text.size());
  EXPECT_EQ(log.lines, 400u);
  for (std::size_t i = 0; i < 400; ++i)
    for (int k = 0; k < 3; ++k) {
      const double g = sim.samples[i].accel[k] / 9.80665, dps = sim.samples[i].gyro[k] * 180.0 / std::numbers::pi;
      EXPECT_NEAR(log.records[i].accel_g[k], std::round(g * 1000.0) / 1000.0, 1e-12);
      EXPECT_NEAR(log.records[i].gyro_dps[k], std::round(dps * 1000.0) / 1000.0, 1e-12);
    }
  const auto tag = read_time_tag(csv.string() + ".tag");
  ASSERT_EQ(tag.records.size(), 400u / 7 + 1);  // 57 groups of 7, then the last 1
  EXPECT_EQ(tag.start_time(), sim.t0);
  EXPECT_EQ(tag.records.back().byte_offset, text.size());  // the CRs are counted
  // Offset of group 1 = the first 7 lines with their CRLF.
  std::size_t seventh = 0;
  for (int i = 0; i < 7; ++i) seventh = text.find("\r\n", seventh) + 2;
  EXPECT_EQ(tag.records[0].byte_offset, seventh);
  EXPECT_EQ(tag.records[0].tick_ms, static_cast<std::uint32_t>(std::llround((sim.samples[6].t - sim.t0) * 1000.0)));
}

TEST_F(ImuPartial, WriterRefusesWhatTheReaderWouldRefuse) {
  auto sim = simulate(10, 0.0, 3);
  const auto csv = dir_ / "w.csv";
  auto ticks = sim.ticks;
  ticks[5] = ticks[4];
  EXPECT_THROW(write_imu_csv_and_tag(csv, sim.samples, ticks, sim.t0), std::invalid_argument);
  auto late = sim.samples;
  late[3].t = sim.t0 - 1.0;  // reached the PC before the start
  EXPECT_THROW(write_imu_csv_and_tag(csv, late, sim.ticks, sim.t0), std::invalid_argument);
  auto nan = sim.samples;
  nan[2].gyro.x() = std::nan("");
  EXPECT_THROW(write_imu_csv_and_tag(csv, nan, sim.ticks, sim.t0), std::invalid_argument);
  EXPECT_THROW(write_imu_csv_and_tag(csv, std::span(sim.samples).first(1), std::span(sim.ticks).first(1), sim.t0),
               std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(csv));
}

// The csv cut at every byte of its last lines, at mid-file and at zero bytes, beside the full
// tag: the records before the cut exactly, the cut line skipped, and the nominal mapping once
// the cut is longer than the scale bound allows.
TEST_F(ImuPartial, CsvCutAtAnyByteKeepsWholeRecordsAndMapsNominally) {
  const auto sim = simulate(3000, 20.0, 4);  // about 22 s
  const auto full_csv = dir_ / "full.csv";
  write_imu_csv_and_tag(full_csv, sim.samples, sim.ticks, sim.t0);
  const std::string text = slurp(full_csv);
  const auto full = read_imu_csv(full_csv);
  const auto tag = read_time_tag(full_csv.string() + ".tag");
  std::vector<std::size_t> line_end;  // byte after each line's newline
  for (std::size_t p = text.find('\n'); p != std::string::npos; p = text.find('\n', p + 1)) line_end.push_back(p + 1);
  ASSERT_EQ(line_end.size(), 3000u);

  std::vector<std::size_t> cuts{0, 10, line_end[0], line_end[1] + 5, text.size() / 2, text.size() - 1};
  for (std::size_t p = line_end[2990]; p < text.size(); ++p) cuts.push_back(p);
  for (const std::size_t cut : cuts) {
    SCOPED_TRACE("cut at byte " + std::to_string(cut));
    const auto csv = write("cut.csv", text.substr(0, cut));
    const auto log = read_imu_csv(csv);
    const auto whole = static_cast<std::size_t>(std::upper_bound(line_end.begin(), line_end.end(), cut) - line_end.begin());
    ASSERT_EQ(log.records.size(), whole);
    EXPECT_EQ(log.skipped_last_line, cut != 0 && (whole == 0 || line_end[whole - 1] != cut));
    for (std::size_t i = 0; i < whole; ++i) {
      ASSERT_EQ(log.records[i].tick_ms, full.records[i].tick_ms);
      ASSERT_EQ(log.records[i].accel_g, full.records[i].accel_g);
      ASSERT_EQ(log.records[i].gyro_dps, full.records[i].gyro_dps);
    }
    if (whole < 2) {
      EXPECT_PARSE_ERROR(to_imu_samples(log, tag), "cut.csv: ", "fewer than 2 records");
      continue;
    }
    ImuTimeMapping m;
    const auto s = to_imu_samples(log, tag, {}, &m);
    ASSERT_EQ(s.size(), whole);
    // A cut shorter than the bound's latency terms (one IMU step here) cannot be told from
    // latency: scaled. One longer than the bound is always found.
    const double missing_s = sim.samples.back().t - sim.samples[whole - 1].t;
    const double bound_s = m.tolerance_ppm * 1e-6 * m.csv_span_s;
    if (missing_s < 0.0095) {
      EXPECT_EQ(m.method, Method::scaled) << m.why;
    }
    if (missing_s > bound_s + 0.002) {
      EXPECT_EQ(m.method, Method::nominal) << m.why;
    }
    if (m.method == Method::nominal) {
      EXPECT_EQ(m.method, Method::nominal) << m.why;
      EXPECT_NE(m.why.find("the csv ends "), std::string::npos) << m.why;
      // The bytes confirm it once the cut exceeds one byte a line (line endings unknown).
      if (log.bytes + log.lines < tag.records.back().byte_offset) {
        EXPECT_NE(m.why.find("the csv is cut short"), std::string::npos) << m.why;
      } else {
        EXPECT_NE(m.why.find("the sizes agree to within the line endings"), std::string::npos) << m.why;
      }
      for (std::size_t i = 0; i < whole; ++i)
        ASSERT_EQ(s[i].t, sim.t0 + static_cast<double>(sim.ticks[i] - sim.ticks[0]) * 1e-3);
      EXPECT_PARSE_ERROR(to_imu_samples(log, tag, ImuConversion{0.0, 9.80665, ImplausibleTickScale::refuse}), "cut.csv: ",
                         "a scale no clock has");
    }
    // Nominal: 20 ppm over 22 s, jitter and rounding. Scaled: stretched by at most the cut.
    const double allowed = 2e-3 + (m.method == Method::scaled ? missing_s : 0.0);
    for (std::size_t i = 0; i < whole; ++i) ASSERT_NEAR(s[i].t, sim.samples[i].t, allowed);
  }
}

// The tag cut mid-record and at half its records, beside the full csv.
TEST_F(ImuPartial, TagCutShortIsReadToItsLastWholeRecord) {
  const auto sim = simulate(3000, 20.0, 5);
  const auto csv = dir_ / "imu.csv";
  write_imu_csv_and_tag(csv, sim.samples, sim.ticks, sim.t0);
  const std::string bytes = slurp(csv.string() + ".tag");
  const auto full = read_time_tag(csv.string() + ".tag");
  ASSERT_EQ(full.records.size(), 3000u);
  const auto log = read_imu_csv(csv);
  for (const std::size_t keep : {std::size_t{1}, std::size_t{1500}, std::size_t{2999}})
    for (const std::size_t extra : {std::size_t{0}, std::size_t{3}, std::size_t{7}}) {
      SCOPED_TRACE(std::to_string(keep) + " records + " + std::to_string(extra) + " bytes");
      const auto path = write("cut.csv.tag", bytes.substr(0, kTimeTagPreambleBytes + 8 * keep + extra));
      const auto tag = read_time_tag(path);
      ASSERT_EQ(tag.records.size(), keep);
      EXPECT_EQ(tag.partial_record_bytes, extra);
      for (std::size_t i = 0; i < keep; ++i) {
        EXPECT_EQ(tag.records[i].tick_ms, full.records[i].tick_ms);
        EXPECT_EQ(tag.records[i].byte_offset, full.records[i].byte_offset);
      }
      if (full.records[keep - 1].tick_ms == 0) continue;
      ImuTimeMapping m;
      const auto s = to_imu_samples(log, tag, {}, &m);
      if (keep < 2999) {
        EXPECT_EQ(m.method, Method::nominal) << m.why;
        EXPECT_NE(m.why.find("the tag ends "), std::string::npos) << m.why;
        EXPECT_NE(m.why.find("the tag is cut short"), std::string::npos) << m.why;
      } else {
        EXPECT_EQ(m.method, Method::scaled) << m.why;
      }
      if (extra) {
        EXPECT_NE(m.why.find("last record was cut (" + std::to_string(extra) + " of 8 bytes"), std::string::npos);
      }
      // Scaled: the samples after the tag's last record are squeezed into its span.
      const double missing_s = sim.samples.back().t - (sim.t0 + tag.records.back().tick_ms * 1e-3);
      EXPECT_NEAR(s.back().t, sim.samples.back().t, 2e-3 + (m.method == Method::scaled ? missing_s : 0.0));
    }
  for (const std::size_t cut : {std::size_t{0}, std::size_t{13}, std::size_t{59}, std::size_t{70}, kTimeTagPreambleBytes})
    EXPECT_THROW(read_time_tag(write("pre.tag", bytes.substr(0, cut))), ParseError) << cut;
}

}  // namespace

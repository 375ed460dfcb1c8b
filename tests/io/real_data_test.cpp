// The readers on the real recordings of shared/data: counts the data README states, time
// order, IMU rate and the IMU clock against the GNSS span, UWB rates per anchor. Skipped
// (failed under CI=true) when the data folder is absent.
#include <gtest/gtest.h>

#include <ctxfuse/io/hanyang_uwb.hpp>
#include <ctxfuse/io/imu_tag.hpp>
#include <ctxfuse/io/rtklib_pos.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>

#include "support/data_dir.hpp"

namespace {

using namespace ctxfuse::io;

TEST(IoRealData, RtklibPosDrive) {
  CTXFUSE_REQUIRE_DATA(pos_path, "gnss-imu-drive/gnss_1934_sf.pos");
  const auto pos = read_rtklib_pos(pos_path);
  ASSERT_EQ(pos.records.size(), 2197u);  // the data README: 2,197 epochs at 4 Hz
  const auto& first = pos.records.front();
  const auto& last = pos.records.back();
  EXPECT_NEAR(first.t, 1752003258.499, 1e-6);  // 2025/07/08 19:34:18.499 GPST
  EXPECT_NEAR(last.t, 1752003807.499, 1e-6);   // 2025/07/08 19:43:27.499 GPST
  EXPECT_NEAR((last.t - first.t) / static_cast<double>(pos.records.size() - 1), 0.25, 1e-3);
  std::size_t fixed = 0;
  for (const auto& r : pos.records) {
    fixed += r.q == 1;
    ASSERT_TRUE(r.has_position_sd() && r.has_velocity()) << "line " << r.line;
  }
  EXPECT_GT(fixed, 2100u);  // "almost all fixed"
  const auto fixes = to_gnss_fixes(pos);
  EXPECT_EQ(fixes.front().cov(0, 0), first.sde_m * first.sde_m);
  EXPECT_TRUE(fixes.front().velocity.has_value());
  std::cout << "pos: " << pos.records.size() << " epochs, " << fixed << " fixed, span " << last.t - first.t << " s\n";
}

TEST(IoRealData, ImuTimeTagOverlapsGnss) {
  CTXFUSE_REQUIRE_DATA(csv_path, "gnss-imu-drive/imu_1934.csv");
  CTXFUSE_REQUIRE_DATA(tag_path, "gnss-imu-drive/imu_1934.csv.tag");
  CTXFUSE_REQUIRE_DATA(pos_path, "gnss-imu-drive/gnss_1934_sf.pos");
  const auto log = read_imu_csv(csv_path);
  const auto tag = read_time_tag(tag_path);
  EXPECT_EQ(log.records.size(), 54860u);  // every line of this copy is whole
  EXPECT_EQ(log.skipped_lines(), 0u);
  EXPECT_EQ(tag.start_s, 1752003261u);
  ImuConversion opt;
  opt.delay_s = -0.125;  // the upstream logging delay
  const auto imu = to_imu_samples(log, tag, opt);
  const double span = imu.back().t - imu.front().t;
  const double rate = static_cast<double>(imu.size() - 1) / span;
  EXPECT_GT(rate, 99.5);
  EXPECT_LT(rate, 100.5);
  EXPECT_NEAR(span, tag.records.back().tick_ms / 1000.0, 1e-6);  // the mapping's definition
  // The IMU clock runs within 0.1 % of the PC's.
  EXPECT_NEAR(ImuClock(log, tag).seconds_per_tick(), 1e-3, 1e-6);

  const auto pos = read_rtklib_pos(pos_path);
  const double gnss_first = pos.records.front().t, gnss_last = pos.records.back().t;
  const double overlap = std::min(gnss_last, imu.back().t) - std::max(gnss_first, imu.front().t);
  EXPECT_LT(std::abs(imu.front().t - gnss_first), 10.0);  // both loggers started within seconds
  EXPECT_LT(std::abs(imu.back().t - gnss_last), 10.0);
  EXPECT_GT(overlap, 0.98 * (gnss_last - gnss_first));
  // At rest at the start (the drive begins parked): |specific force| is about g.
  EXPECT_NEAR(imu.front().accel.norm(), 9.80665, 0.3);
  std::cout << "imu: " << imu.size() << " samples, " << log.skipped_lines() << " partial lines skipped, " << rate
            << " Hz, first " << imu.front().t - gnss_first << " s after GNSS, last " << imu.back().t - gnss_last
            << " s after, overlap " << overlap << " s, " << tag.records.size() << " tag records\n";
}

// The drive maps exactly as the data README's upstream formula (bit for bit), and the same csv
// cut at 1 MB beside its full tag is not stretched over the tag's span: nominal 1 ms ticks.
TEST(IoRealData, ImuDriveScaledAsUpstreamAndCutCsvNominal) {
  CTXFUSE_REQUIRE_DATA(csv_path, "gnss-imu-drive/imu_1934.csv");
  CTXFUSE_REQUIRE_DATA(tag_path, "gnss-imu-drive/imu_1934.csv.tag");
  const auto log = read_imu_csv(csv_path);
  const auto tag = read_time_tag(tag_path);
  ImuTimeMapping m;
  const auto imu = to_imu_samples(log, tag, {}, &m);
  EXPECT_EQ(m.method, ImuTimeMapping::Method::scaled) << m.why;
  EXPECT_NEAR(m.scale_ppm, 257.0, 0.1) << m.why;  // 548.731 s of tag over 548.590 s of ticks
  EXPECT_EQ(m.csv_bytes + m.csv_lines, m.tag_last_offset);  // LF here, CRLF when logged
  const double start = tag.start_s + tag.start_fraction_s, tick0 = static_cast<double>(log.records.front().tick_ms);
  const double ratio = (tag.records.back().tick_ms / 1000.0) / (static_cast<double>(log.records.back().tick_ms) - tick0);
  for (std::size_t i = 0; i < imu.size(); ++i)
    ASSERT_EQ(imu[i].t, start + (static_cast<double>(log.records[i].tick_ms) - tick0) * ratio) << i;

  const auto dir = std::filesystem::temp_directory_path() / "ctxfuse_io_real_cut_imu";
  std::filesystem::create_directories(dir);
  {
    std::ifstream in(csv_path, std::ios::binary);
    std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    std::ofstream(dir / "imu.csv", std::ios::binary) << text.substr(0, 1000000);
  }
  const auto cut = read_imu_csv(dir / "imu.csv");
  std::filesystem::remove_all(dir);
  ImuTimeMapping mc;
  const auto part = to_imu_samples(cut, tag, {}, &mc);
  EXPECT_EQ(mc.method, ImuTimeMapping::Method::nominal) << mc.why;
  EXPECT_NE(mc.why.find("the csv is cut short"), std::string::npos) << mc.why;
  ASSERT_EQ(part.size(), 22228u);
  const double rate = static_cast<double>(part.size() - 1) / (part.back().t - part.front().t);
  EXPECT_GT(rate, 99.5);  // not the 40.5 Hz of a stretch over the tag's 549 s
  EXPECT_LT(rate, 100.5);
  // The part read nominally departs from the full recording's mapping by the fitted 257 ppm
  // over its 222 s, 57 ms at its end.
  double worst = 0.0;
  for (std::size_t i = 0; i < part.size(); ++i) {
    ASSERT_EQ(part[i].t, start + (static_cast<double>(cut.records[i].tick_ms) - tick0) * 1e-3);
    worst = std::max(worst, std::abs(part[i].t - imu[i].t));
  }
  EXPECT_NEAR(worst, m.scale_ppm * 1e-6 * mc.csv_span_s, 1e-6);
  std::cout << "cut drive: " << part.size() << " samples, " << rate << " Hz; " << mc.why << "\n";
}

TEST(IoRealData, HanyangDynamicCases) {
  CTXFUSE_REQUIRE_DATA(root, "uwb-outdoor-hanyang/Dynamic_measurements");
  for (const std::string c : {"LOS/Trajectory_A/Case_1", "LOS/Trajectory_A/Case_2", "NLOS/Trajectory_A/Case_1",
                              "NLOS/Trajectory_A/Case_2"}) {
    SCOPED_TRACE(c);
    const auto uwb = read_hanyang_uwb(root / c);
    const auto ref = read_hanyang_reference(root / c);
    ASSERT_EQ(uwb.ranges_per_anchor.size(), 4u);
    for (const int id : {3, 5, 9, 12}) ASSERT_TRUE(uwb.ranges_per_anchor.count(id)) << id;
    for (std::size_t i = 1; i < uwb.ranges.size(); ++i) ASSERT_LE(uwb.ranges[i - 1].t_ns, uwb.ranges[i].t_ns);
    const double span = uwb.ranges.back().range.t - uwb.ranges.front().range.t;
    std::cout << c << ": " << uwb.ranges.size() << " ranges over " << span << " s;";
    for (const auto& [id, n] : uwb.ranges_per_anchor) {
      const double rate = static_cast<double>(n) / span;
      std::cout << " A" << id << " " << n << " (" << rate << " Hz)";
      EXPECT_GT(rate, 7.5) << "anchor " << id;  // 10 Hz nominal, with dropped exchanges
      EXPECT_LT(rate, 10.5) << "anchor " << id;
    }
    std::cout << "; " << uwb.non_finite_rssi << " non-finite rssi; reference " << ref.size() << " samples\n";
    EXPECT_EQ(uwb.non_finite_rssi, c == "NLOS/Trajectory_A/Case_2" ? 1u : 0u);
    // The reference (8 Hz) covers the ranging on the same clock: it starts with it and runs
    // through it (in some cases on beyond the last range).
    const double overlap = std::min(ref.back().t, uwb.ranges.back().range.t) - std::max(ref.front().t, uwb.ranges.front().range.t);
    std::cout << "  reference from " << ref.front().t - uwb.ranges.front().range.t << " s to "
              << ref.back().t - uwb.ranges.back().range.t << " s about the ranges' ends\n";
    EXPECT_LT(std::abs(ref.front().t - uwb.ranges.front().range.t), 1.0);
    EXPECT_GT(overlap, 0.98 * span);
    EXPECT_NEAR(static_cast<double>(ref.size() - 1) / (ref.back().t - ref.front().t), 8.0, 0.2);
  }
}

}  // namespace

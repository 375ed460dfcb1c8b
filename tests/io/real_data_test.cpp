// The readers on the real recordings of shared/data: counts the data README states, time
// order, IMU rate and the IMU clock against the GNSS span, UWB rates per anchor. Skipped
// (failed under CI=true) when the data folder is absent.
#include <gtest/gtest.h>

#include <ctxfuse/io/hanyang_uwb.hpp>
#include <ctxfuse/io/imu_tag.hpp>
#include <ctxfuse/io/rtklib_pos.hpp>

#include <algorithm>
#include <cmath>
#include <iostream>
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

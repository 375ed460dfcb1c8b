// The GNSS/INS pipeline on the real car drive (../shared/data/gnss-imu-drive; skipped without
// it, a failure under CI=true), with the usual outage protocol: 15 s outages every 45 s from
// 40 s after the first GNSS epoch (11 windows), GNSS at 1 Hz outside them, horizontal error at
// the RTK-fixed epochs inside. The figures are the ones in docs/results.md (section gins_real),
// held to 2 % so that a change in the filter that moves them shows here.
#include <gtest/gtest.h>

#include "ctxfuse/studies/gins_outages.hpp"
#include "ctxfuse/instances/gins_nav20.hpp"
#include "support/data_dir.hpp"

namespace {
using namespace ctxfuse;
namespace gins = ctxfuse::pipelines::gins;

TEST(GinsRealDrive, OutageErrorsWithAndWithoutConstraints) {
  CTXFUSE_REQUIRE_DATA(dir, "gnss-imu-drive");
  const gins::Recording rec = gins::read_recording(dir);
  gins::RunOptions o;
  o.installation = ctxfuse::studies::gnss_imu_drive_installation();
  o.outages = ctxfuse::studies::standard_outages();
  o.gnss_rate_hz = ctxfuse::studies::kStandardGnssRateHz;

  const gins::RunResult none = gins::run<gins::Nav20>(rec.imu, rec.fixes, gins::Settings{}, o);
  o.constraints.zupt = o.constraints.nhc = true;
  o.smooth = true;
  const gins::RunResult both = gins::run<gins::Nav20>(rec.imu, rec.fixes, gins::Settings{}, o);
  ASSERT_TRUE(none.aligned && both.aligned);
  ASSERT_TRUE(both.smooth_status.accepted());
  ASSERT_EQ(both.windows.size(), 11u);
  const auto s_none = ctxfuse::studies::score_outages(rec.fixes, none), s_both = ctxfuse::studies::score_outages(rec.fixes, both);
  // The first window opens 2.2 s after the car first moves, before any alignment can happen.
  EXPECT_EQ(s_both.outages_scored, 10u);
  EXPECT_EQ(s_both.forward.epochs, 600u);
  // The static start that sets the noise figures of pipelines/gins/settings.hpp.
  EXPECT_EQ(both.static_start.samples, 3061u);
  EXPECT_NEAR(both.static_start.gyro_std.maxCoeff() / gins::kDeg, 2.324, 0.001);
  EXPECT_NEAR(both.static_start.accel_std.maxCoeff(), 0.130, 0.001);
  EXPECT_EQ(both.static_start.allan_differences, 33u);
  EXPECT_NEAR(both.static_start.gyro_allan_1s.maxCoeff() / gins::kDeg, 0.0991, 0.0001);
  EXPECT_NEAR(both.static_start.accel_allan_1s.maxCoeff(), 0.0147, 0.0001);
  // No IMU gap on the drive: one alignment, never lost.
  EXPECT_EQ(both.counts.imu_losses + both.counts.realignments, 0u);

  auto near = [](double measured, double expected) { EXPECT_NEAR(measured, expected, 0.02 * expected); };
  near(s_none.forward.rms, 4.125);
  near(s_none.forward.max, 19.00);
  near(s_both.forward.rms, 1.025);
  near(s_both.forward.max, 3.960);
  near(s_both.smoothed.rms, 0.288);
  near(s_both.smoothed.max, 0.709);
  // The targets: forward with ZUPT + NHC <= 2 m RMS and <= 8 m max, smoothed <= 0.3 m.
  EXPECT_LT(s_both.forward.rms, 2.0);
  EXPECT_LT(s_both.forward.max, 8.0);
  EXPECT_LT(s_both.smoothed.rms, 0.3);
  std::printf("none %.3f / %.3f m, zupt+nhc %.3f / %.3f m, smoothed %.3f / %.3f m, records %.1f MB\n", s_none.forward.rms,
              s_none.forward.max, s_both.forward.rms, s_both.forward.max, s_both.smoothed.rms, s_both.smoothed.max,
              both.record_bytes / 1e6);
}

}  // namespace

// The GNSS/INS pipeline (pipelines/gins/run.hpp) end to end on a simulated drive
// (drive_sim.hpp: 10 m/s with weaving, a 5 s stop inside a 15 s outage): io streams in, rows
// out at every GNSS stamp, the outage withheld, the constraints cutting the outage error, the
// RTS pass below the forward one in error and in every 1-sigma.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "ctxfuse/eval/gins_outages.hpp"
#include "drive_sim.hpp"
#include "gins_nav20.hpp"

namespace {
using namespace ctxfuse;
using namespace ctxfuse::test;
namespace gins = ctxfuse::pipelines::gins;

constexpr double kT0 = 1.75e9;  // a GPS-like epoch, so stamps carry the recording's magnitude

struct SimRecording {
  std::vector<io::ImuSample> imu;
  std::vector<io::GnssFix> fixes;   // 4 Hz, 2 cm noise, the filter's input
  std::vector<eval::TimedLatLon> truth;
};

const SimRecording& recording() {
  static const SimRecording r = [] {
    SimRecording s;
    const Drive d = simulate_drive(
        80.0, [](double t) { return speed_with_stop(t, 25.0, 5.0); },
        [](double t) { return 0.08 * std::sin(2.0 * 3.14159265 * t / 20.0) * speed_with_stop(t, 25.0, 5.0) / 10.0; },
        Eigen::Vector3d(0.02, -0.03, 0.04) * kDeg, Eigen::Vector3d(0.02, -0.01, 0.03), 7);
    sim::Rng rng(7, sim::Stream::gnss);
    for (std::size_t k = 0; k < d.steps.size(); ++k) {
      const DriveStep& st = d.steps[k];
      // A rate sample holds from its stamp to the next: the step's mean rate at its start.
      s.imu.push_back({kT0 + st.t - d.dt, st.imu.dtheta / d.dt, st.imu.dv / d.dt, false});
      if (k % 25 != 24) continue;
      const Eigen::Vector3d llh = st.truth.get<"p">();
      s.truth.push_back({kT0 + st.t, llh(0), llh(1)});
      io::GnssFix f;
      f.t = kT0 + st.t;
      f.frame = io::PositionFrame::geodetic;
      // Draws in index order (an argument list's order of evaluation differs between compilers).
      auto draw3 = [&] {
        Eigen::Vector3d n;
        for (int i = 0; i < 3; ++i) n(i) = rng.normal();
        return n;
      };
      const Eigen::Vector3d noisy = earth::GeodeticRetraction::inject(llh, 0.02 * draw3());
      f.position = {noisy(0) / kDeg, noisy(1) / kDeg, noisy(2)};
      f.cov = Eigen::Matrix3d::Identity() * 0.02 * 0.02;
      const Eigen::Vector3d v = st.truth.get<"v">();
      f.velocity = Eigen::Vector3d(v(1), v(0), -v(2)) + 0.02 * draw3();
      f.velocity_cov = Eigen::Matrix3d::Identity() * 0.02 * 0.02;
      f.quality = io::FixQuality::fixed;
      s.fixes.push_back(f);
    }
    return s;
  }();
  return r;
}

gins::RunResult run(gins::Constraints c, bool smooth) {
  gins::RunOptions o;
  o.constraints = c;
  o.outages = {15.0, 45.0, 20.0, 30.0};  // one window, 20-35 s after the first fix
  o.gnss_rate_hz = 1.0;
  o.smooth = smooth;
  return gins::run<gins::Nav20>(recording().imu, recording().fixes, gins::Settings{}, o);
}

eval::OutageErrors errors(const gins::RunResult& r, const std::vector<gins::TrajectoryRow>& rows) {
  return eval::outage_errors(eval::lat_lon_of(rows), recording().truth, r.windows);
}

TEST(GinsPipeline, RowsAtEveryFixAndTheOutageWithheld) {
  const gins::RunResult r = run({}, false);
  ASSERT_TRUE(r.aligned);
  ASSERT_EQ(r.windows.size(), 1u);
  const double first = recording().fixes.front().t;
  EXPECT_DOUBLE_EQ(r.windows[0].start, first + 20.0);
  // Aligned on the second fix kept at 1 Hz (1 s after the first, 10 m apart).
  EXPECT_DOUBLE_EQ(r.alignment_time, first + 1.0);
  // One row per fix from the alignment on (no constraint epochs without constraints), but for
  // the last fix, which comes at the end of the last IMU sample's interval: the replay has
  // nothing to propagate it with.
  std::size_t fixes_after = 0;
  for (const auto& f : recording().fixes) fixes_after += f.t >= r.alignment_time ? 1 : 0;
  EXPECT_EQ(r.replay.streams[0].beyond_imu, 1u);
  ASSERT_EQ(r.forward.size(), fixes_after - 1);
  std::size_t used = 0;
  for (const auto& row : r.forward) {
    if (r.windows[0].contains(row.t)) {
      EXPECT_FALSE(row.gnss_used) << row.t - first;
    }
    used += row.gnss_used ? 1 : 0;
  }
  // 1 Hz from the alignment (first + 1 s) to the last kept fix (first + 79 s), less the 15 in
  // the outage; every one accepted by the gate.
  EXPECT_EQ(used, 79u - 15u);
  EXPECT_EQ(r.counts.gnss_used, used - 1);  // the alignment fix starts the filter, no update
  EXPECT_EQ(r.counts.gnss_gated, 0u);
  EXPECT_EQ(r.counts.gnss_withheld, 15u);
  EXPECT_EQ(r.counts.imu_refused + r.counts.filter_failures, 0u);
}

TEST(GinsPipeline, ConstraintsCutTheOutageErrorAndRtsCutsItFurther) {
  const gins::RunResult none = run({}, false);
  gins::Constraints zn;
  zn.zupt = zn.nhc = true;
  const gins::RunResult both = run(zn, true);
  const auto e_none = errors(none, none.forward), e_both = errors(both, both.forward), e_rts = errors(both, both.smoothed);
  ASSERT_EQ(e_none.epochs, 60u);
  ASSERT_EQ(e_both.epochs, 60u);
  EXPECT_GT(both.counts.zupt, 0u);
  EXPECT_GT(both.counts.nhc, 0u);
  EXPECT_LT(e_both.rms, 0.3 * e_none.rms) << e_both.rms << " vs " << e_none.rms;
  EXPECT_LT(e_rts.rms, 0.2 * e_both.rms) << e_rts.rms << " vs " << e_both.rms;
  ASSERT_TRUE(both.smooth_status.accepted());
  ASSERT_EQ(both.smoothed.size(), both.forward.size());
  for (std::size_t k = 0; k < both.forward.size(); ++k) {
    for (int i = 0; i < 3; ++i) {
      EXPECT_LE(both.smoothed[k].sd_position(i), both.forward[k].sd_position(i) * (1 + 1e-9) + 1e-12) << k;
      EXPECT_LE(both.smoothed[k].sd_velocity(i), both.forward[k].sd_velocity(i) * (1 + 1e-9) + 1e-12) << k;
    }
  }
  EXPECT_GT(both.record_bytes, both.forward.size() * sizeof(Eigen::Matrix<double, 20, 20>));
  std::printf("outage RMS / max [m]: none %.3f / %.3f, zupt+nhc %.3f / %.3f, smoothed %.3f / %.3f\n", e_none.rms, e_none.max,
              e_both.rms, e_both.max, e_rts.rms, e_rts.max);
}

}  // namespace

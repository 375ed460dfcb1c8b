// The GNSS/INS pipeline (pipelines/gins/run.hpp) end to end on a simulated drive
// (drive_sim.hpp: 10 m/s with weaving, a 5 s stop inside a 15 s outage): io streams in, rows
// out at every GNSS stamp, the outage withheld, the constraints cutting the outage error, the
// RTS pass below the forward one in error and in every 1-sigma; the magnetometer stream
// replayed with them holding the heading after the stop.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "ctxfuse/studies/gins_outages.hpp"
#include "drive_sim.hpp"
#include "ctxfuse/instances/gins_nav20.hpp"

namespace {
using namespace ctxfuse;
using namespace ctxfuse::test;
namespace gins = ctxfuse::pipelines::gins;

constexpr double kT0 = 1.75e9;  // a GPS-like epoch, so stamps carry the recording's magnitude

struct SimRecording {
  std::vector<messages::ImuSample> imu;
  std::vector<messages::GnssFix> fixes;   // 4 Hz, 2 cm noise, the filter's input
  std::vector<messages::MagSample> mag;   // 10 Hz, IMU (= body) axes, 0.05 uT noise
  std::vector<ctxfuse::studies::TimedLatLon> truth;
  std::vector<std::pair<double, double>> heading;  // (t, true heading [rad]) at each fix
};

// A field of 30 uT north, 0.5 uT east, 35 uT down (dip 49 deg), the same everywhere.
const Eigen::Vector3d kFieldNed(30.0, 0.5, 35.0);

const SimRecording& recording() {
  static const SimRecording r = [] {
    SimRecording s;
    const Drive d = simulate_drive(
        80.0, [](double t) { return speed_with_stop(t, 25.0, 5.0); },
        [](double t) { return 0.08 * std::sin(2.0 * 3.14159265 * t / 20.0) * speed_with_stop(t, 25.0, 5.0) / 10.0; },
        Eigen::Vector3d(0.02, -0.03, 0.04) * kDeg, Eigen::Vector3d(0.02, -0.01, 0.03), 7);
    sim::Rng rng(7, sim::Stream::gnss);
    sim::Rng mag_rng(7, sim::Stream::magnetometer);
    for (std::size_t k = 0; k < d.steps.size(); ++k) {
      const DriveStep& st = d.steps[k];
      // A rate sample holds from its stamp to the next: the step's mean rate at its start.
      s.imu.push_back({kT0 + st.t - d.dt, st.imu.dtheta / d.dt, st.imu.dv / d.dt, false});
      const Eigen::Matrix3d C_nb = st.truth.get<"theta">().toRotationMatrix();
      if (k % 10 == 9) {
        Eigen::Vector3d n;
        for (int i = 0; i < 3; ++i) n(i) = 0.05 * mag_rng.normal();
        s.mag.push_back({kT0 + st.t, C_nb.transpose() * kFieldNed + n});
      }
      if (k % 25 != 24) continue;
      s.heading.emplace_back(kT0 + st.t, models::heading_of(C_nb));
      const Eigen::Vector3d llh = st.truth.get<"p">();
      s.truth.push_back({kT0 + st.t, llh(0), llh(1)});
      messages::GnssFix f;
      f.t = kT0 + st.t;
      f.frame = messages::PositionFrame::geodetic;
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
      f.quality = messages::FixQuality::fixed;
      s.fixes.push_back(f);
    }
    return s;
  }();
  return r;
}

gins::RunResult run(gins::Constraints c, bool smooth, bool with_mag = false) {
  gins::RunOptions o;
  o.constraints = c;
  if (with_mag) o.mag = recording().mag;
  o.outages = {15.0, 45.0, 20.0, 30.0};  // one window, 20-35 s after the first fix
  o.gnss_rate_hz = 1.0;
  o.smooth = smooth;
  return gins::run<gins::Nav20>(recording().imu, recording().fixes, gins::Settings{}, o);
}

ctxfuse::studies::OutageErrors errors(const gins::RunResult& r, const std::vector<gins::TrajectoryRow>& rows) {
  return ctxfuse::studies::outage_errors(ctxfuse::studies::lat_lon_of(rows), recording().truth, r.windows);
}

TEST(GinsPipeline, RowsAtEveryFixAndTheOutageWithheld) {
  const gins::RunResult r = run({}, false);
  ASSERT_TRUE(r.aligned);
  ASSERT_EQ(r.windows.size(), 1u);
  const double first = recording().fixes.front().t;
  EXPECT_DOUBLE_EQ(r.windows[0].start, first + 20.0);
  // Aligned on the first fix: it moves at 10 m/s and reports its velocity to 2 cm/s (a heading
  // sigma of 0.1 deg).
  EXPECT_DOUBLE_EQ(r.alignment_time, first);
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
  // 1 Hz from the alignment (the first fix) to the last kept fix (first + 79 s), less the 15
  // in the outage; every one accepted by the gate.
  EXPECT_EQ(used, 80u - 15u);
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
  // The drive's one stop (25-30 s) lies inside the outage, where the filter's speed has drifted
  // by more than static_max_speed_mps (0.1 m/s): a still IMU is then not taken for a stop (a
  // steady platform reads as still too), so no ZUPT; NHC alone bounds the drift.
  EXPECT_EQ(both.counts.zupt, 0u);
  EXPECT_GT(both.counts.static_but_moving, 0u);
  EXPECT_GT(both.counts.nhc, 0u);
  EXPECT_LT(e_both.rms, 0.45 * e_none.rms) << e_both.rms << " vs " << e_none.rms;
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

// Signed heading error [rad] (estimate - truth) at the fix stamped t0 + at_s (the first fix
// at or after it that has a row).
double heading_error_at(const gins::RunResult& r, double at_s) {
  const double t = recording().fixes.front().t + at_s;
  const auto& truth = recording().heading;
  for (const auto& row : r.forward) {
    if (row.t < t - 1e-6) continue;
    for (const auto& [tt, h] : truth)
      if (std::abs(tt - row.t) < 1e-6) return PlanarAngleRetraction::wrap(row.rpy(2) - h);
  }
  return NAN;
}

TEST(GinsPipeline, MagnetometerStreamHoldsTheHeadingThroughTheOutage) {
  // The relative heading (models::MagRelativeHeading) starts at the first static sample after
  // the alignment and holds the change of the heading since then: it cannot remove the error
  // the heading had at that epoch, only slow its drift. Over the outage (20-35 s after the
  // first fix, gyros alone) the error changed by 0.498 deg without the magnetometer and
  // 0.414 deg with it (2 deg per sample, 10 Hz).
  gins::Constraints m;
  m.mag = true;
  const gins::RunResult without = run({}, false), with = run(m, false, true), not_fed = run(m, false, false);
  EXPECT_GT(with.counts.mag, 500u);  // 10 Hz over most of the 80 s drive
  EXPECT_EQ(with.replay.streams[1].delivered + with.replay.streams[1].beyond_imu, recording().mag.size());
  EXPECT_EQ(not_fed.counts.mag, 0u);  // the flag alone reads nothing
  const double drift_without = heading_error_at(without, 35.0) - heading_error_at(without, 20.0);
  const double drift_with = heading_error_at(with, 35.0) - heading_error_at(with, 20.0);
  std::printf("heading error change over the outage [deg]: without mag %.4f, with %.4f; error at 20 s %.4f / %.4f; mag used %zu, gated %zu\n",
              drift_without / kDeg, drift_with / kDeg, heading_error_at(without, 20.0) / kDeg, heading_error_at(with, 20.0) / kDeg,
              with.counts.mag, with.counts.mag_gated);
  EXPECT_LT(std::abs(drift_with), 0.9 * std::abs(drift_without));
}

// After a fault has led the filter astray beyond what its covariance admits (an accelerometer
// offset of 0.6 m/s^2 through the 15 s outage: 9 m/s and some 70 m off at its end), the fixes'
// positions and velocities are both refused by the gate; three in a row of each are released
// (Settings::gate_release, filters/release.hpp) and the filter is back on the fixes.
// With releases off it is not.
TEST(GinsPipeline, GnssPositionAndVelocityAreReleasedAfterAnImuFault) {
  const double t_first = recording().fixes.front().t;
  std::vector<messages::ImuSample> imu = recording().imu;
  for (auto& u : imu)
    if (u.t >= t_first + 20.0 && u.t < t_first + 35.0) u.accel.x() += 0.6;
  gins::RunOptions o;
  o.outages = {15.0, 45.0, 20.0, 30.0};  // the fault's window, 20-35 s after the first fix
  o.gnss_rate_hz = 1.0;
  auto run_with = [&](int release_count) {
    gins::Settings s;
    s.gate_release.min_rejections = release_count;
    return gins::run<gins::Nav20>(imu, recording().fixes, s, o);
  };
  // Horizontal position [m] and velocity [m/s] error against the fix at t_first + at_s.
  auto off_at = [&](const gins::RunResult& r, double at_s) {
    const double t = t_first + at_s;
    for (const auto& row : r.forward) {
      if (std::abs(row.t - t) > 1e-6) continue;
      for (const auto& f : recording().fixes) {
        if (std::abs(f.t - t) > 1e-6) continue;
        const double dn = (row.llh(0) - f.position(0) * kDeg) * 6378137.0;
        const double de = (row.llh(1) - f.position(1) * kDeg) * 6378137.0 * std::cos(row.llh(0));
        const double dv = std::hypot(row.velocity_ned(0) - f.velocity->y(), row.velocity_ned(1) - f.velocity->x());
        return std::pair{std::hypot(dn, de), dv};
      }
    }
    return std::pair{double(NAN), double(NAN)};
  };
  const gins::RunResult released = run_with(gins::Settings{}.gate_release.min_rejections);
  const gins::RunResult never = run_with(1000000);
  const auto [p_end, v_end] = off_at(never, 35.0);
  const auto [p_rel, v_rel] = off_at(released, 45.0);
  const auto [p_never, v_never] = off_at(never, 45.0);
  std::printf("at the outage's end %.1f m / %.2f m/s off; 10 s later: released %.3f m / %.3f m/s "
              "(position %zu, velocity %zu released), never released %.1f m / %.2f m/s\n",
              p_end, v_end, p_rel, v_rel, released.counts.gnss_released, released.counts.velocity_released, p_never, v_never);
  EXPECT_GT(p_end, 30.0);
  EXPECT_GT(v_end, 5.0);
  EXPECT_GE(released.counts.gnss_released, 1u);
  EXPECT_GE(released.counts.velocity_released, 1u);
  EXPECT_EQ(never.counts.gnss_released + never.counts.velocity_released, 0u);
  // Back on the fixes (2 cm, 0.02 m/s noise) within 10 s of the outage's end (with the
  // position's release alone, the velocity's taken out of ForwardPass, 0.86 m / 0.53 m/s off
  // then, after 6 position releases) ...
  EXPECT_LT(p_rel, 0.1);
  EXPECT_LT(v_rel, 0.05);
  // ... which the gate alone does not do.
  EXPECT_GT(p_never, 10.0);
}

// An IMU at 10 Hz (each sample the mean rate of ten of the 100 Hz ones, in force for 0.1 s,
// half of it past Settings::imu_hold_s) is never taken for a gap: every new sample ends the
// unmeasured time, so the pass is never lost, and it tracks as at 100 Hz.
TEST(GinsPipeline, ASlowImuIsNeverTakenForAGap) {
  const auto& fast = recording().imu;
  std::vector<messages::ImuSample> slow;
  for (std::size_t k = 0; k + 10 <= fast.size(); k += 10) {
    messages::ImuSample u = fast[k];
    for (std::size_t j = 1; j < 10; ++j) {
      u.gyro += fast[k + j].gyro;
      u.accel += fast[k + j].accel;
    }
    u.gyro /= 10.0;
    u.accel /= 10.0;
    slow.push_back(u);
  }
  gins::RunOptions o;
  o.outages = {15.0, 45.0, 20.0, 30.0};
  o.gnss_rate_hz = 1.0;
  const gins::RunResult at10 = gins::run<gins::Nav20>(slow, recording().fixes, gins::Settings{}, o);
  const gins::RunResult at100 = gins::run<gins::Nav20>(fast, recording().fixes, gins::Settings{}, o);
  ASSERT_TRUE(at10.aligned);
  EXPECT_EQ(at10.counts.imu_losses, 0u);
  EXPECT_EQ(at10.counts.realignments, 0u);
  EXPECT_EQ(at10.forward.size(), at100.forward.size());
  const auto e10 = errors(at10, at10.forward), e100 = errors(at100, at100.forward);
  std::printf("outage RMS at 10 Hz %.3f m, at 100 Hz %.3f m\n", e10.rms, e100.rms);
  EXPECT_LT(e10.rms, 2.0 * e100.rms);
}

}  // namespace

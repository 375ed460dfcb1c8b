// Scoring a GNSS/INS run (pipelines/gins) with the outage protocol (studies/outage_protocol.hpp):
// the reference is the recording's own RTK-fixed epochs, read here and never by the pipeline.
// Also the installation of the gnss-imu-drive recording, as its data README gives it.
#pragma once

#include <cmath>
#include <span>
#include <vector>

#include "ctxfuse/studies/outage_protocol.hpp"
#include "ctxfuse/pipelines/gins/run.hpp"

namespace ctxfuse::studies {

/// gnss-imu-drive (data README, upstream configuration): IMU axes -> body by roll 180, pitch
/// -6.79, yaw 185.35 deg; IMU at (0, 0, -0.65) m and GNSS antenna at (0, -0.05, -0.65) m from
/// the system origin (forward, right, down); logging delay -0.125 s.
inline pipelines::gins::Installation gnss_imu_drive_installation() {
  pipelines::gins::Installation i;
  i.imu_rpy_deg = {180.0, -6.79, 185.35};
  i.imu_lever_m = {0.0, 0.0, -0.65};
  i.gnss_lever_m = {0.0, -0.05, -0.65};
  i.imu_delay_s = -0.125;
  return i;
}

inline std::vector<TimedLatLon> lat_lon_of(std::span<const pipelines::gins::TrajectoryRow> rows) {
  std::vector<TimedLatLon> v;
  v.reserve(rows.size());
  for (const auto& r : rows) v.push_back({r.t, r.llh(0), r.llh(1)});
  return v;
}

struct GinsOutageScores {
  OutageErrors forward, smoothed;  // smoothed: empty unless the run smoothed
  std::size_t outages_scored = 0;  // windows with at least one scored epoch (forward)
};

inline GinsOutageScores score_outages(std::span<const messages::GnssFix> fixes, const pipelines::gins::RunResult& run) {
  const auto ref = rtk_fixed_reference(fixes);
  GinsOutageScores s;
  s.forward = outage_errors(lat_lon_of(run.forward), ref, run.windows);
  if (!run.smoothed.empty()) s.smoothed = outage_errors(lat_lon_of(run.smoothed), ref, run.windows);
  for (const auto& o : s.forward.outages) s.outages_scored += o.epochs > 0 ? 1 : 0;
  return s;
}

/// The whole run against a reference: the horizontal error at every RTK-fixed reference epoch
/// inside the trajectory's span (one window over the reference's span; epochs outside the
/// trajectory are counted as unscored).
inline GinsOutageScores score_whole_run(std::span<const messages::GnssFix> reference, const pipelines::gins::RunResult& run) {
  const auto ref = rtk_fixed_reference(reference);
  GinsOutageScores s;
  if (ref.empty()) return s;
  const pipelines::gins::OutageWindow all[1] = {{ref.front().t, std::nextafter(ref.back().t, ref.back().t + 1.0)}};
  s.forward = outage_errors(lat_lon_of(run.forward), ref, all);
  if (!run.smoothed.empty()) s.smoothed = outage_errors(lat_lon_of(run.smoothed), ref, all);
  s.outages_scored = s.forward.epochs > 0 ? 1 : 0;
  return s;
}

}  // namespace ctxfuse::studies

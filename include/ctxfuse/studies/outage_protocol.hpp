// The GNSS-outage evaluation of a GNSS/INS trajectory against an RTK reference (the usual one
// on the gnss-imu-drive recording, data README): simulated outages (pipelines/gins
// OutageSchedule: by default 15 s every 45 s, the first 40 s after the first GNSS epoch, as
// long as a window ends 30 s before the last), GNSS decimated to 1 Hz outside them, and the
// horizontal error at every RTK-fixed reference epoch (Q = 1) inside an outage, the trajectory
// interpolated linearly (in latitude and longitude) to the reference's stamp. RMS and maximum
// over all those epochs, and per outage.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/models/earth.hpp"
#include "ctxfuse/pipelines/gins/gnss_schedule.hpp"

namespace ctxfuse::studies {

/// The protocol's schedule and rate.
inline pipelines::gins::OutageSchedule standard_outages() { return {15.0, 45.0, 40.0, 30.0}; }
inline constexpr double kStandardGnssRateHz = 1.0;

struct TimedLatLon {
  double t = 0.0;
  double lat = 0.0, lon = 0.0;  // [rad]
};

/// Reference epochs: the RTK-fixed (Q = 1) fixes, geodetic, in radians.
inline std::vector<TimedLatLon> rtk_fixed_reference(std::span<const messages::GnssFix> fixes) {
  constexpr double deg = 3.14159265358979323846 / 180.0;
  std::vector<TimedLatLon> out;
  for (const auto& f : fixes)
    if (f.quality == messages::FixQuality::fixed && f.frame == messages::PositionFrame::geodetic)
      out.push_back({f.t, f.position(0) * deg, f.position(1) * deg});
  return out;
}

/// Linear interpolation of a time-ordered trajectory to t; nothing outside its span.
inline bool interpolate(std::span<const TimedLatLon> traj, double t, TimedLatLon& out) {
  if (traj.empty() || t < traj.front().t || t > traj.back().t) return false;
  const auto it = std::lower_bound(traj.begin(), traj.end(), t, [](const TimedLatLon& a, double x) { return a.t < x; });
  if (it->t == t) {
    out = *it;
    return true;
  }
  const TimedLatLon& b = *it;
  const TimedLatLon& a = *(it - 1);
  const double w = (t - a.t) / (b.t - a.t);
  out = {t, a.lat + w * (b.lat - a.lat), a.lon + w * std::remainder(b.lon - a.lon, 2.0 * 3.14159265358979323846)};
  return true;
}

struct OutageError {
  pipelines::gins::OutageWindow window;
  std::size_t epochs = 0;  // reference epochs scored in it
  double rms = 0.0, max = 0.0;
};

struct OutageErrors {
  std::vector<OutageError> outages;
  std::size_t epochs = 0;
  std::size_t unscored = 0;  // reference epochs inside an outage but outside the trajectory's span
  double rms = 0.0, max = 0.0;
};

/// Horizontal error [m] of the trajectory, interpolated to a reference epoch's time, at that
/// epoch; nothing outside the trajectory's span.
inline std::optional<double> horizontal_error_at(std::span<const TimedLatLon> traj, const TimedLatLon& ref) {
  TimedLatLon est;
  if (!interpolate(traj, ref.t, est)) return std::nullopt;
  const Eigen::Vector3d per = earth::ned_per_llh(ref.lat, 0.0);
  const double dn = (est.lat - ref.lat) * per(0);
  const double de = std::remainder(est.lon - ref.lon, 2.0 * 3.14159265358979323846) * per(1);
  return std::sqrt(dn * dn + de * de);
}

/// Horizontal error [m] of the trajectory at every reference epoch inside a window.
inline OutageErrors outage_errors(std::span<const TimedLatLon> traj, std::span<const TimedLatLon> reference,
                                  std::span<const pipelines::gins::OutageWindow> windows) {
  OutageErrors r;
  double sum2 = 0.0;
  for (const auto& w : windows) {
    OutageError e{w};
    double s2 = 0.0;
    for (const auto& ref : reference) {
      if (!w.contains(ref.t)) continue;
      const std::optional<double> err = horizontal_error_at(traj, ref);
      if (!err) {
        ++r.unscored;
        continue;
      }
      s2 += *err * *err;
      ++e.epochs;
      e.max = std::max(e.max, *err);
    }
    e.rms = e.epochs ? std::sqrt(s2 / static_cast<double>(e.epochs)) : 0.0;
    sum2 += s2;
    r.epochs += e.epochs;
    r.max = std::max(r.max, e.max);
    r.outages.push_back(e);
  }
  r.rms = r.epochs ? std::sqrt(sum2 / static_cast<double>(r.epochs)) : 0.0;
  return r;
}

}  // namespace ctxfuse::studies

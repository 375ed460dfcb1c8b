// The simulated drive as what a recording would hold: sensor streams without truth
// (messages::SensorLog, what a pipeline runs on) and the truth and labels apart (sim::TruthLog,
// what scoring reads). The simulator is one producer of streams among the readers.
#pragma once

#include <vector>

#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/sim/drive.hpp"
#include "ctxfuse/sim/records.hpp"

namespace ctxfuse::sim {

/// The receiver's epoch as a message: the satellites it tracked and its DOPs (NaN when the
/// simulator reports -1: fewer than four satellites).
inline messages::SatEpoch sat_epoch(const Drive& d, const GnssEpoch& e) {
  messages::SatEpoch out;
  out.t = e.t;
  for (const auto& s : d.satellites_of(e)) out.sats.push_back({s.sat_id, s.elevation_deg, s.azimuth_deg, s.cn0_dbhz});
  out.pdop = e.pdop < 0.0 ? messages::kUnknown : e.pdop;
  out.hdop = e.hdop < 0.0 ? messages::kUnknown : e.hdop;
  return out;
}

/// A fix as the receiver reports it: position and its reported standard deviations.
inline messages::GnssFix gnss_fix(const GnssEpoch& e) {
  messages::GnssFix f;
  f.t = e.t;
  f.position = e.position;
  f.frame = messages::PositionFrame::local_enu;
  f.cov = Eigen::Vector3d(e.std_horizontal_m * e.std_horizontal_m, e.std_horizontal_m * e.std_horizontal_m,
                          e.std_vertical_m * e.std_vertical_m)
              .asDiagonal();
  f.quality = messages::FixQuality::single;
  f.satellites_used = e.num_sats;
  return f;
}

inline messages::UwbRange uwb_range(const UwbRange& r) {
  return {r.t, r.anchor_id, r.anchor_position, r.range_m, r.rssi_dbm, r.rssi_first_path_dbm};
}

/// Every sensor stream of the drive, without truth.
inline messages::SensorLog sensor_log(const Drive& d) {
  messages::SensorLog log;
  log.imu = d.imu;  // the simulator's samples are the messages (sim/records.hpp)
  for (const auto& e : d.gnss) {
    log.sat_epochs.push_back(sat_epoch(d, e));
    if (e.has_fix) log.gnss.push_back(gnss_fix(e));
  }
  log.uwb.reserve(d.uwb.size());
  for (const auto& r : d.uwb) log.uwb.push_back(uwb_range(r));
  for (const auto& s : d.speed) log.speed.push_back({s.t, s.speed_mps});
  for (const auto& m : d.mag) log.mag.push_back({m.t, m.field_ut});
  return log;
}

/// The drive's truth and labels.
inline TruthLog truth_log(const Drive& d) {
  TruthLog out;
  out.truth = d.truth;
  for (const auto& r : d.uwb) out.uwb.push_back({r.t, r.anchor_id, r.nlos, r.true_range_m, r.nlos_bias_m});
  for (const auto& s : d.sats) out.sats.push_back({s.t, s.sat_id, s.line_of_sight});
  for (const auto& e : d.gnss)
    if (e.has_fix) out.fixes.push_back({e.t, e.error, e.multipath_bias});
  return out;
}

}  // namespace ctxfuse::sim

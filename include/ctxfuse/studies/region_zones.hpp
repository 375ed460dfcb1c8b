// What the region study measures per zone of a simulated drive (`ctxfuse region-study` prints
// it): the zones themselves, the simulator's sensor picture in each (from the drive's truth:
// this is scoring, not estimation), and the gate decisions of each estimator's takers, counted
// through the region pipeline's update observer.
//
// Zones (truth position at the measurement time): out-far (outdoor, > 30 m from the approach's
// street mouth), out-near (outdoor within 30 m of it), tr-mouth / tr-door (street half / door
// half of the covered approach), in-door10 (indoor, within 10 m of the door plane x = 0),
// in-deep (the rest of the garage). They split the paper's three regions where the sensor
// picture changes: GNSS degrades towards the door, UWB (NLOS) away from it.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cstddef>
#include <limits>
#include <map>
#include <set>
#include <utility>

#include "ctxfuse/eval/truth.hpp"
#include "ctxfuse/pipelines/region_imm/aided.hpp"
#include "ctxfuse/sim/drive.hpp"

namespace ctxfuse::studies::region_zones {

inline constexpr int kZones = 6;
inline constexpr std::array<const char*, kZones> kZoneName{"out-far", "out-near", "tr-mouth", "tr-door", "in-door10", "in-deep"};
inline constexpr double kNearMouthM = 30.0, kDoorDepthM = 10.0;

/// The zone of a position or of the truth at a time, on one drive's world.
struct Zoning {
  const sim::Drive& d;
  double mouth_x = 0.0;  // x of the approach's street end (west side of the transition polygon)
  explicit Zoning(const sim::Drive& drive) : d(drive), mouth_x(std::numeric_limits<double>::infinity()) {
    for (const auto& v : d.world().transition.vertices) mouth_x = std::min(mouth_x, v.x());
  }
  int at(const Eigen::Vector2d& p) const {
    switch (d.world().region_at(p)) {
      case sim::Region::outdoor: return (p - Eigen::Vector2d(mouth_x, 0.0)).norm() <= kNearMouthM ? 1 : 0;
      case sim::Region::transition: return p.x() < 0.5 * mouth_x ? 2 : 3;
      case sim::Region::indoor: return p.x() <= kDoorDepthM ? 4 : 5;
    }
    return 0;
  }
  int at_time(double t) const { return at(eval::position_at(d.truth, t).head<2>()); }
};

/// The simulator's sensor picture in one zone (sums; the report divides).
struct ZonePicture {
  int gnss_epochs = 0, fixes = 0;
  double fix_error_sum = 0.0, multipath_sum = 0.0;
  int uwb_epochs = 0, ranges = 0, nlos = 0;
  double range_error_sum = 0.0, nlos_bias_sum = 0.0, nlos_bias_max = 0.0;
  std::set<int> anchors;
};
using Picture = std::array<ZonePicture, kZones>;

template <class = void>
Picture sensor_picture(const sim::Drive& d, const Zoning& zones) {
  Picture p;
  for (const auto& e : d.gnss) {
    auto& z = p[static_cast<std::size_t>(zones.at_time(e.t))];
    ++z.gnss_epochs;
    if (!e.has_fix) continue;
    ++z.fixes;
    z.fix_error_sum += e.error.head<2>().norm();
    z.multipath_sum += e.multipath_bias.head<2>().norm();
  }
  // Epochs of the UWB clock, whether or not any anchor answered.
  for (long k = 0;; ++k) {
    const double t = static_cast<double>(k) / d.config.uwb.rate_hz;
    if (t > d.duration()) break;
    ++p[static_cast<std::size_t>(zones.at_time(t))].uwb_epochs;
  }
  for (const auto& r : d.uwb) {
    auto& z = p[static_cast<std::size_t>(zones.at_time(r.t))];
    ++z.ranges;
    z.range_error_sum += r.range_m - r.true_range_m;
    z.anchors.insert(r.anchor_id);
    if (!r.nlos) continue;
    ++z.nlos;
    z.nlos_bias_sum += r.nlos_bias_m;
    z.nlos_bias_max = std::max(z.nlos_bias_max, r.nlos_bias_m);
  }
  return p;
}

/// The drive's NLOS truth per range, keyed by (time, anchor) as UpdateEvent names a range.
using NlosTruth = std::map<std::pair<double, int>, bool>;
inline NlosTruth nlos_truth(const sim::Drive& d) {
  NlosTruth nlos;
  for (const auto& u : d.uwb) nlos[{u.t, u.anchor_id}] = u.nlos;
  return nlos;
}

// Takers of an update: the FKF's local filter (one column), or the IMM's modes ODR, I-OTR, IDR
// and the IMM as a whole (the update is gated by the IMM when no mode that took it accepted it;
// that is what ImmSink::imm_health counts for its lock-out recovery).
inline constexpr int kMaxTakers = pipelines::region_imm::kMaxTakers;
inline constexpr std::array<const char*, kMaxTakers> kImmTaker{"odr", "iotr", "idr", "imm"};

struct ZoneGates {
  int offered = 0, gated = 0, nlos_offered = 0, nlos_accepted = 0;
};
using GateTable = std::array<std::array<std::array<ZoneGates, kZones>, kMaxTakers>, 2>;  // [gnss 0 / uwb 1][taker][zone]

/// Counts, per zone, the GNSS and UWB updates each taker was offered and gated, and how the
/// NLOS ranges among them fared. An UpdateObserver of the region pipeline.
struct GateCounter {
  const Zoning& zones;
  const NlosTruth& nlos;
  GateTable& table;
  void operator()(const pipelines::region_imm::UpdateEvent& ev) {
    const auto zone = static_cast<std::size_t>(zones.at_time(ev.t));
    const bool gnss = ev.source == pipelines::region_imm::Source::gnss;
    bool is_nlos = false;
    if (!gnss)
      if (const auto it = nlos.find({ev.t, ev.anchor_id}); it != nlos.end()) is_nlos = it->second;
    for (std::size_t j = 0; j < static_cast<std::size_t>(std::min(ev.takers, kMaxTakers)); ++j) {
      if (!ev.offered[j]) continue;
      auto& c = table[gnss ? 0 : 1][j][zone];
      ++c.offered;
      c.gated += ev.gated[j] ? 1 : 0;
      if (is_nlos) {
        ++c.nlos_offered;
        c.nlos_accepted += ev.gated[j] ? 0 : 1;
      }
    }
  }
};

}  // namespace ctxfuse::studies::region_zones

// What `ctxfuse region-study` measures per zone of a simulated drive: the zones themselves,
// the simulator's sensor picture in each (from the drive's truth: this is scoring, not
// estimation), and the gate decisions of each estimator's takers, counted through the
// pipeline's update observer.
//
// Zones (truth position at the measurement time): out-far (outdoor, > 30 m from the approach's
// street mouth), out-near (outdoor within 30 m of it), tr-mouth / tr-door (street half / door
// half of the covered approach), in-door10 (indoor, within 10 m of the door plane x = 0),
// in-deep (the rest of the garage). They split the paper's three regions where the sensor
// picture changes: GNSS degrades towards the door, UWB (NLOS) away from it.
#pragma once

#include <algorithm>
#include <array>
#include <cstdio>
#include <limits>
#include <map>
#include <ostream>
#include <set>
#include <string>
#include <utility>

#include "cli/json.hpp"
#include "cli/formatted.hpp"
#include "ctxfuse/eval/truth.hpp"
#include "ctxfuse/pipelines/region_imm.hpp"
#include "ctxfuse/sim/drive.hpp"

namespace ctxfuse::cli::region_study {

namespace ri = pipelines::region_imm;

inline constexpr int kZones = 6;
inline constexpr std::array<const char*, kZones> kZoneName{"out-far", "out-near", "tr-mouth", "tr-door", "in-door10", "in-deep"};
inline constexpr double kNearMouthM = 30.0, kDoorDepthM = 10.0;

// ------------------------------------------------------------------ zones
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

// ------------------------------------------------------------------ sensor picture
struct ZonePicture {
  int gnss_epochs = 0, fixes = 0;
  double fix_error_sum = 0.0, multipath_sum = 0.0;
  int uwb_epochs = 0, ranges = 0, nlos = 0;
  double range_error_sum = 0.0, nlos_bias_sum = 0.0, nlos_bias_max = 0.0;
  std::set<int> anchors;
};
using Picture = std::array<ZonePicture, kZones>;

inline Picture sensor_picture(const sim::Drive& d, const Zoning& zones) {
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

inline double mean(double sum, int n) { return n > 0 ? sum / n : 0.0; }

inline void report_picture(const Picture& p, std::ostream& out, Json& json) {
  out << "  zone       gnssEp  fixes  fixErr   |mp|  | uwbEp  rng/ep  nlos%  nlosBias(max)  meanRngErr  anchors\n";
  for (int k = 0; k < kZones; ++k) {
    const auto& z = p[static_cast<std::size_t>(k)];
    std::string anchors;
    Json::Array ids;
    for (int a : z.anchors) {
      if (!anchors.empty()) anchors += ',';
      anchors += std::to_string(a);
      ids.emplace_back(a);
    }
    const double fix_err = mean(z.fix_error_sum, z.fixes), mp = mean(z.multipath_sum, z.fixes);
    const double per_epoch = mean(z.ranges, z.uwb_epochs), nlos_share = mean(z.nlos, z.ranges);
    const double bias = mean(z.nlos_bias_sum, z.nlos), range_err = mean(z.range_error_sum, z.ranges);
    out << formatted("  %-10s %6d %6d  %6.2f  %5.2f  | %5d  %5.2f  %5.1f  %5.2f (%5.2f)    %6.2f    %s\n", kZoneName[static_cast<std::size_t>(k)],
               z.gnss_epochs, z.fixes, fix_err, mp, z.uwb_epochs, per_epoch, 100.0 * nlos_share, bias, z.nlos_bias_max, range_err,
               anchors.empty() ? "-" : anchors.c_str());
    Json& j = json[kZoneName[static_cast<std::size_t>(k)]];
    j["gnss_epochs"] = z.gnss_epochs;
    j["fixes"] = z.fixes;
    j["fix_error_mean_m"] = fix_err;
    j["multipath_mean_m"] = mp;
    j["uwb_epochs"] = z.uwb_epochs;
    j["ranges"] = z.ranges;
    j["ranges_per_epoch"] = per_epoch;
    j["nlos_ranges"] = z.nlos;
    j["nlos_share"] = nlos_share;
    j["nlos_bias_mean_m"] = bias;
    j["nlos_bias_max_m"] = z.nlos_bias_max;
    j["range_error_mean_m"] = range_err;
    j["anchors"] = Json(std::move(ids));
  }
}

// ------------------------------------------------------------------ gate bookkeeping
// Takers of an update: the FKF's local filter (one column), or the IMM's modes ODR, I-OTR, IDR
// and the IMM as a whole (the update is gated by the IMM when no mode that took it accepted it;
// that is what ImmSink::imm_health counts for its lock-out recovery).
inline constexpr int kMaxTakers = ri::kMaxTakers;
inline constexpr std::array<const char*, kMaxTakers> kImmTaker{"odr", "iotr", "idr", "imm"};

struct ZoneGates {
  int offered = 0, gated = 0, nlos_offered = 0, nlos_accepted = 0;
};
using GateTable = std::array<std::array<std::array<ZoneGates, kZones>, kMaxTakers>, 2>;  // [gnss 0 / uwb 1][taker][zone]

/// Counts, per zone, the GNSS and UWB updates each taker was offered and gated, and how the
/// NLOS ranges among them fared (labels from the drive's truth, matched by time and anchor).
struct GateCounter {
  const Zoning& zones;
  const std::map<std::pair<double, int>, bool>& nlos;
  GateTable& table;
  void operator()(const ri::UpdateEvent& ev) {
    const auto zone = static_cast<std::size_t>(zones.at_time(ev.t));
    const bool gnss = ev.source == ri::Source::gnss;
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

inline void report_gates(const char* label, const GateTable& table, int taker_count, std::ostream& out, Json& json) {
  for (int src = 0; src < 2; ++src) {
    for (int j = 0; j < taker_count; ++j) {
      const auto& row = table[static_cast<std::size_t>(src)][static_cast<std::size_t>(j)];
      const char* taker = taker_count > 1 ? kImmTaker[static_cast<std::size_t>(j)] : "";
      out << formatted("    %-10s %s%s%-4s:", label, src == 0 ? "GNSS" : "UWB ", taker_count > 1 ? "/" : "", taker);
      Json& jt = taker_count > 1 ? json[src == 0 ? "gnss" : "uwb"][taker] : json[src == 0 ? "gnss" : "uwb"];
      if (std::none_of(row.begin(), row.end(), [](const ZoneGates& z) { return z.offered > 0; })) {
        out << " (never offered)\n";
        jt = Json("never offered");
        continue;
      }
      for (int k = 0; k < kZones; ++k) {
        const auto& z = row[static_cast<std::size_t>(k)];
        out << formatted("  %s %d/%d", kZoneName[static_cast<std::size_t>(k)], z.gated, z.offered);
        Json& jz = jt[kZoneName[static_cast<std::size_t>(k)]];
        jz["offered"] = z.offered;
        jz["gated"] = z.gated;
        if (src == 1) {
          jz["nlos_offered"] = z.nlos_offered;
          jz["nlos_accepted"] = z.nlos_accepted;
          if (z.nlos_offered > 0) out << formatted(" (nlos acc %d/%d)", z.nlos_accepted, z.nlos_offered);
        }
      }
      out << '\n';
    }
  }
}

}  // namespace ctxfuse::cli::region_study

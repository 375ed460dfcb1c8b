// How `ctxfuse region-study` prints its per-zone tables: the sensor picture and the gate
// counts of studies/region_zones.hpp (which defines the zones and counts), as text and JSON.
#pragma once

#include <algorithm>
#include <ostream>
#include <string>
#include <utility>

#include "cli/json.hpp"
#include "cli/formatted.hpp"
#include "ctxfuse/studies/region_zones.hpp"

namespace ctxfuse::cli::region_study {

using namespace studies::region_zones;

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

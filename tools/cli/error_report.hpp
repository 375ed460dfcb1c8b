// Printing and JSON for position-error statistics, shared by `ctxfuse run` and `ctxfuse demo`.
#pragma once

#include <cstdio>
#include <ostream>
#include <string>
#include <vector>

#include "cli/json.hpp"
#include "ctxfuse/eval/position_error.hpp"
#include "ctxfuse/sim/world.hpp"

namespace ctxfuse::cli {

inline Json stats_json(const eval::PositionErrorStats& s) {
  Json j;
  j["count"] = static_cast<double>(s.count);
  j["mean_h_m"] = s.horizontal.mean;
  j["rmse_h_m"] = s.horizontal.rmse;
  j["max_h_m"] = s.horizontal.max;
  j["std_h_m"] = s.horizontal.std;
  j["rmse_east_m"] = s.rmse_axis.x();
  j["rmse_north_m"] = s.rmse_axis.y();
  j["rmse_up_m"] = s.rmse_axis.z();
  Json p;
  for (std::size_t i = 0; i < eval::kPercentileLevels.size(); ++i) {
    char key[16];
    std::snprintf(key, sizeof key, "p%d", static_cast<int>(eval::kPercentileLevels[i]));
    p[key] = s.horizontal.percentiles[i];
  }
  j["cdf_h_m"] = std::move(p);
  return j;
}

/// One line per region plus "overall": n, mean, RMSE (E, N, horizontal), MAX, STD, 67 % and 95 %.
inline void print_region_table(std::ostream& out, const std::vector<eval::PositionErrorStats>& by_region,
                               const eval::PositionErrorStats& overall) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "  %-11s %6s %7s %7s %7s %7s %7s %7s %7s %7s\n", "region", "n", "mean", "rmse_E", "rmse_N",
                "rmse_H", "max", "std", "p67", "p95");
  out << buf;
  auto row = [&](const char* name, const eval::PositionErrorStats& s) {
    std::snprintf(buf, sizeof buf, "  %-11s %6zu %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f\n", name, s.count, s.horizontal.mean,
                  s.rmse_axis.x(), s.rmse_axis.y(), s.horizontal.rmse, s.horizontal.max, s.horizontal.std, s.horizontal.at(67),
                  s.horizontal.at(95));
    out << buf;
  };
  for (std::size_t r = 0; r < by_region.size(); ++r) row(sim::region_name(static_cast<sim::Region>(r)), by_region[r]);
  row("overall", overall);
}

}  // namespace ctxfuse::cli

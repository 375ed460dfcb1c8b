// `ctxfuse features uwb-static`: NLOS features per range of static UWB ranging recordings
// (ctxfuse/io/uwb_static.hpp reads them, ctxfuse/features/nlos.hpp windows them).
#include <array>
#include <cstdio>
#include <map>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <ctxfuse/features/nlos.hpp>
#include <ctxfuse/io/uwb_static.hpp>

#include "cli/features_common.hpp"
#include "cli/options.hpp"

namespace ctxfuse::cli::features_cli {

namespace feat = ctxfuse::features;

int run_uwb_static(Args args, std::ostream& out, std::ostream& err) {
  auto app = make_app("features uwb-static",
                      "Reads DIR/{LOS,NLOS}/height_<h>cm/<d>m.csv and writes one row per range: label (1 NLOS, 0 LOS),\n"
                      "true_distance_m, then with --window 1 range_residual_m (measured - true), rssi_dbm, rssi_minus_fp_db;\n"
                      "with --window N > 1 the causal statistics of the recording's last N ranges: residual_mean_m,\n"
                      "residual_std_m, rssi_mean_dbm, rssi_minus_fp_mean_db. Prints the mean residual per height.");
  std::string dir, out_path;
  std::vector<double> heights;
  int window = 1;
  bool height_column = false;
  app.add_option("--data", dir, "folder holding LOS/ and NLOS/")->required();
  app.add_option("--out", out_path, "feature CSV")->required();
  app.add_option("--heights", heights, "keep only these antenna heights [cm] (comma-separated; default: all)")->delimiter(',');
  app.add_option("--window", window, "ranges per causal window (1 = single range)")->check(CLI::Range(1, 64));
  app.add_flag("--height-column", height_column, "append a height_cm column (a group column for `classify train --groups`)");
  if (const auto status = parse_options(app, args, out, err)) return *status;
  ctxfuse::io::UwbStaticReadStats stats;
  std::vector<ctxfuse::io::UwbStaticRange> ranges;
  try {
    ranges = ctxfuse::io::read_uwb_static_dataset(dir, heights, stats);
  } catch (const ctxfuse::io::UwbDataError& e) {
    err << "ctxfuse features uwb-static: " << e.what() << '\n';
    return 1;
  }
  if (ranges.empty()) {
    err << "ctxfuse features uwb-static: no ranges found under '" << dir << "' for the requested heights\n";
    return 1;
  }
  auto f = open_out(out_path);
  if (window == 1)
    *f << "label,true_distance_m,range_residual_m,rssi_dbm,rssi_minus_fp_db";
  else
    *f << "label,true_distance_m,residual_mean_m,residual_std_m,rssi_mean_dbm,rssi_minus_fp_mean_db";
  *f << (height_column ? ",height_cm\n" : "\n");
  feat::RangeWindowFeatures<64> stats_window(window);
  std::size_t nlos = 0, current_file = static_cast<std::size_t>(-1);
  struct Sum {
    double residual = 0.0;
    std::size_t n = 0;
  };
  std::map<double, std::array<Sum, 2>> per_height;
  for (const auto& r : ranges) {
    if (r.file_index != current_file) {
      stats_window.reset();
      current_file = r.file_index;
    }
    auto& s = per_height[r.height_cm][r.nlos ? 1 : 0];
    s.residual += r.range_residual_m();
    ++s.n;
    nlos += r.nlos;
    *f << (r.nlos ? 1 : 0) << ',' << fmt(r.true_distance_m);
    if (window == 1) {
      *f << ',' << fmt(r.range_residual_m()) << ',' << fmt(r.rssi_dbm) << ',' << fmt(r.rssi_minus_first_path_db());
    } else {
      feat::RangeWindowFeatures<64>::Output o;
      // The reader refused non-finite values, so a refusal here is a bug, not bad data.
      if (const ctxfuse::Status st = stats_window.push(r.range_residual_m(), r.rssi_dbm, r.first_path_rssi_dbm, o); !st)
        throw std::logic_error("uwb-static window: " + std::string(ctxfuse::describe(st.problem)));
      *f << ',' << fmt(o.residual_mean_m) << ',' << fmt(o.residual_std_m) << ',' << fmt(o.rssi_mean_dbm) << ','
         << fmt(o.rssi_minus_first_path_mean_db);
    }
    if (height_column) *f << ',' << fmt(r.height_cm);
    *f << '\n';
  }
  out << "uwb-static: " << stats.files << " files, " << ranges.size() << " ranges (" << nlos << " NLOS, "
      << ranges.size() - nlos << " LOS), " << stats.skipped_non_finite_power
      << " rows skipped for non-finite RSSI -> " << out_path << '\n';
  out << "height_cm  LOS_ranges  LOS_mean_residual_m  NLOS_ranges  NLOS_mean_residual_m  NLOS_minus_LOS_m\n";
  for (const auto& [h, s] : per_height) {
    const double los = s[0].n ? s[0].residual / double(s[0].n) : std::nan("");
    const double nl = s[1].n ? s[1].residual / double(s[1].n) : std::nan("");
    char line[160];
    std::snprintf(line, sizeof line, "%9.1f  %10zu  %19.4f  %11zu  %20.4f  %16.4f\n", h, s[0].n, los, s[1].n, nl, nl - los);
    out << line;
  }
  return 0;
}

}  // namespace ctxfuse::cli::features_cli

// `ctxfuse features gnss`: the scene-detection paper's eight features per epoch from a
// per-satellite CSV (ctxfuse/features/gnss_scene.hpp), with the receivers' conventions: rows of
// one epoch in any order and any mix of constellations, unknown elevation or azimuth (-91, empty,
// out of range) = a tracked satellite without geometry, windows in seconds; optionally joined
// with a label CSV by time so that the output feeds `ctxfuse classify` as it is.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include <ctxfuse/features/gnss_scene.hpp>
#include <ctxfuse/io/text.hpp>

#include "cli/features_common.hpp"
#include "cli/options.hpp"

namespace ctxfuse::cli::features_cli {
namespace {

namespace feat = ctxfuse::features;

struct SatRow {
  std::size_t line = 0;  // in the satellite CSV
  feat::SatelliteObservation sat;
  double pdop = std::nan("");
};

}  // namespace

int run_gnss(Args args, std::ostream& out, std::ostream& err) {
  auto app = make_app("features gnss",
                      "Reads a per-satellite CSV (header names time_s, sat_id, elevation_deg, azimuth_deg, cn0_dbhz and\n"
                      "optionally pdop; any order, other columns ignored) and writes time_s + the eight scene features per\n"
                      "epoch (stdout without --out). Rows with the same time_s form one epoch, in any order and mix of\n"
                      "constellations. Empty cn0_dbhz = in view, not tracked. Elevation empty or outside [-90, 90] (u-blox:\n"
                      "-91) or azimuth empty or outside [0, 360] = tracked without geometry: counted and in the C/N0\n"
                      "features, not in mean elevation, azimuth vacancy or computed PDOP. A row with an empty sat_id marks\n"
                      "an epoch with no satellites. With --labels, only epochs with a label are written, as\n"
                      "time_s,label,features (what `ctxfuse classify` reads; it ignores time_s).");
  std::string sats_path, out_path, labels_path;
  double tolerance = 0.05;
  feat::GnssSceneConfig config;
  app.add_option("--sats", sats_path, "per-satellite CSV")->required();
  app.add_option("--out", out_path, "feature CSV (default: stdout)");
  app.add_option("--labels", labels_path, "CSV with columns time_s and label: each epoch takes the label nearest in time");
  app.add_option("--label-tolerance", tolerance, "largest |epoch time - label time| [s] of a join")->check(ctxfuse::cli::kNonNegativeNumber);
  add_window_options(app, config);
  if (const auto status = parse_options(app, args, out, err)) return *status;
  try {
    io::TextFile sat_file(sats_path);
    const io::Header header = io::read_header(sat_file, io::Separator::comma);
    const std::size_t c_time = io::require_column(sat_file, header, "time_s"), c_id = io::require_column(sat_file, header, "sat_id"),
                      c_el = io::require_column(sat_file, header, "elevation_deg"),
                      c_az = io::require_column(sat_file, header, "azimuth_deg"),
                      c_cn0 = io::require_column(sat_file, header, "cn0_dbhz");
    const auto c_pdop = header.find("pdop");
    // Epochs by time; rows of one epoch may come in any order.
    std::map<double, std::vector<SatRow>> epochs;
    std::map<std::string, int> ids;
    std::size_t without_geometry = 0;
    io::Fields row(sat_file.name(), &header);
    while (io::next_fields(sat_file, row, io::Separator::comma)) {
      row.expect_count(header.size());
      const double time = row.real(c_time, io::kAnyFinite);
      auto& epoch = epochs[time];
      SatRow s;
      s.line = row.line();
      if (c_pdop && !row[*c_pdop].empty()) {
        s.pdop = row.real(*c_pdop, io::kAnyFinite);
        if (!(s.pdop > 0.0)) row.fail(*c_pdop, io::quote(row[*c_pdop]) + " is not a positive number");
      }
      // Adds the row to its epoch, whose rows must agree on the pdop.
      const auto add = [&] {
        for (const auto& o : epoch)
          if (std::isfinite(s.pdop) && std::isfinite(o.pdop) && o.pdop != s.pdop)
            row.fail(*c_pdop, io::cat(io::quote(row[*c_pdop]), " differs from the epoch's other pdop (line ", o.line, ")"));
        epoch.push_back(s);
      };
      if (row[c_id].empty()) {  // epoch marker without satellites
        s.sat.id = -1;
        add();
        continue;
      }
      s.sat.id = ids.emplace(row[c_id], static_cast<int>(ids.size())).first->second;
      // Any spelling of a number, inf and nan included: what is not in range is unknown.
      const double el = row[c_el].empty() ? std::nan("") : row.real(c_el, io::kAnyReal);
      const double az = row[c_az].empty() ? std::nan("") : row.real(c_az, io::kAnyReal);
      const bool known = std::abs(el) <= 90.0 && az >= 0.0 && az <= 360.0;  // false for NaN
      s.sat.elevation_deg = known ? el : std::nan("");
      s.sat.azimuth_deg = known ? az : std::nan("");
      if (!row[c_cn0].empty()) s.sat.cn0_dbhz = row.real_in(c_cn0, 0.0, 100.0);
      if (!known && std::isfinite(s.sat.cn0_dbhz)) ++without_geometry;
      for (const auto& o : epoch)
        if (o.sat.id == s.sat.id)
          row.fail(c_id, io::cat(io::quote(row[c_id]), " appears twice in the epoch at time_s ", fmt(time), " (also line ", o.line, ")"));
      add();
    }
    // Labels by time.
    std::vector<std::pair<double, int>> labels;
    if (!labels_path.empty()) {
      io::TextFile label_file(labels_path);
      const io::Header label_header = io::read_header(label_file, io::Separator::comma);
      const std::size_t c_t = io::require_column(label_file, label_header, "time_s"),
                        c_label = io::require_column(label_file, label_header, "label");
      io::Fields label_row(label_file.name(), &label_header);
      while (io::next_fields(label_file, label_row, io::Separator::comma)) {
        label_row.expect_count(label_header.size());
        const double time = label_row.real(c_t, io::kAnyFinite);
        labels.emplace_back(time, label_row.whole<int>(c_label, -1'000'000'000, 1'000'000'000));
      }
      std::sort(labels.begin(), labels.end());
    }
    const auto label_of = [&](double time) -> std::optional<int> {
      const auto it = std::lower_bound(labels.begin(), labels.end(), std::pair{time, std::numeric_limits<int>::min()});
      std::optional<std::pair<double, int>> best;
      if (it != labels.end()) best = *it;
      if (it != labels.begin() && (!best || time - std::prev(it)->first < best->first - time)) best = *std::prev(it);
      if (!best || std::abs(best->first - time) > tolerance) return std::nullopt;
      return best->second;
    };

    std::unique_ptr<std::ofstream> file_out;
    if (!out_path.empty()) file_out = open_out(out_path);
    std::ostream& os = file_out ? *file_out : out;
    os << (labels_path.empty() ? "time_s" : "time_s,label");
    for (const auto& n : feat::kGnssSceneFeatureNames) os << ',' << n;
    os << '\n';
    feat::GnssSceneExtractor<> extractor(config);
    std::vector<feat::SatelliteObservation> sats;
    std::size_t written = 0, unlabelled = 0;
    for (const auto& [time, rows] : epochs) {
      sats.clear();
      double pdop = std::nan("");
      for (const auto& s : rows) {
        if (std::isfinite(s.pdop)) pdop = s.pdop;  // the same in every row that has one
        if (s.sat.id >= 0) sats.push_back(s.sat);
      }
      feat::GnssSceneFeatures f;
      const auto status = extractor.push({time, sats, pdop}, f);
      if (!status)
        throw io::ParseError(sat_file.name(), rows.front().line, 0, "",
                             io::cat("epoch at time_s ", fmt(time), ": ", ctxfuse::describe(status.problem)));
      std::optional<int> label;
      if (!labels_path.empty() && !(label = label_of(time))) {
        ++unlabelled;
        continue;
      }
      os << fmt(time);
      if (label) os << ',' << *label;
      for (double v : f) os << ',' << fmt(v);
      os << '\n';
      ++written;
    }
    err << "features gnss: " << epochs.size() << " epochs from " << sats_path << ", " << without_geometry
        << " tracked satellite rows without geometry (elevation/azimuth unknown)";
    if (!labels_path.empty()) err << ", " << written << " labelled, " << unlabelled << " without a label within " << fmt(tolerance) << " s";
    err << '\n';
    return 0;
  } catch (const std::exception& e) {
    err << "ctxfuse features gnss: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace ctxfuse::cli::features_cli

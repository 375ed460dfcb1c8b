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
#include <ctxfuse/io/uwb_static.hpp>  // detail::split_csv_line, detail::parse_field

#include "cli/features_common.hpp"
#include "cli/options.hpp"

namespace ctxfuse::cli::features_cli {
namespace {

namespace feat = ctxfuse::features;
using ctxfuse::io::detail::parse_field;
using ctxfuse::io::detail::split_csv_line;

struct Table {
  std::vector<std::string> names;
  std::vector<std::vector<std::string>> rows;
  std::vector<std::size_t> lines;  // line number of each row
  int column(std::string_view name) const {
    const auto it = std::find(names.begin(), names.end(), name);
    return it == names.end() ? -1 : static_cast<int>(it - names.begin());
  }
};

Table read_table(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot open '" + path + "'");
  Table t;
  std::string line;
  std::size_t line_no = 1;
  if (!std::getline(in, line)) throw InputError(path + ":1: empty file (no header)");
  for (auto n : split_csv_line(line)) t.names.emplace_back(n);
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line == "\r") continue;
    const auto f = split_csv_line(line);
    if (f.size() != t.names.size())
      throw InputError(path + ":" + std::to_string(line_no) + ": " + std::to_string(f.size()) + " fields, header has " +
                       std::to_string(t.names.size()));
    t.rows.emplace_back(f.begin(), f.end());
    t.lines.push_back(line_no);
  }
  return t;
}

struct SatRow {
  std::size_t row = 0;
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
    const Table t = read_table(sats_path);
    const int c_time = t.column("time_s"), c_id = t.column("sat_id"), c_el = t.column("elevation_deg"),
              c_az = t.column("azimuth_deg"), c_cn0 = t.column("cn0_dbhz"), c_pdop = t.column("pdop");
    for (auto [c, n] : {std::pair{c_time, "time_s"}, {c_id, "sat_id"}, {c_el, "elevation_deg"}, {c_az, "azimuth_deg"}, {c_cn0, "cn0_dbhz"}})
      if (c < 0) throw InputError(sats_path + ":1: column '" + n + "' missing from the header");
    const auto fail = [&](std::size_t r, int c, std::string_view why) {
      return InputError(sats_path + ":" + std::to_string(t.lines[r]) + ": column '" + t.names[static_cast<std::size_t>(c)] + "': '" +
                        t.rows[r][static_cast<std::size_t>(c)] + "' " + std::string(why));
    };
    // Epochs by time; rows of one epoch may come in any order.
    std::map<double, std::vector<SatRow>> epochs;
    std::map<std::string, int> ids;
    std::size_t without_geometry = 0;
    for (std::size_t r = 0; r < t.rows.size(); ++r) {
      const auto& f = t.rows[r];
      const auto field = [&](int c) -> const std::string& { return f[static_cast<std::size_t>(c)]; };
      double time = 0;
      if (!parse_field(field(c_time), time) || !std::isfinite(time)) throw fail(r, c_time, "is not a finite time");
      auto& epoch = epochs[time];
      SatRow s;
      s.row = r;
      if (c_pdop >= 0 && !field(c_pdop).empty() &&
          (!parse_field(field(c_pdop), s.pdop) || !(s.pdop > 0.0) || !std::isfinite(s.pdop)))
        throw fail(r, c_pdop, "is not a positive number");
      if (field(c_id).empty()) {  // epoch marker without satellites
        s.sat.id = -1;
        epoch.push_back(s);
        continue;
      }
      s.sat.id = ids.emplace(field(c_id), static_cast<int>(ids.size())).first->second;
      double el = std::nan(""), az = std::nan("");
      if (!field(c_el).empty() && !parse_field(field(c_el), el)) throw fail(r, c_el, "is not a number");
      if (!field(c_az).empty() && !parse_field(field(c_az), az)) throw fail(r, c_az, "is not a number");
      const bool known = std::abs(el) <= 90.0 && az >= 0.0 && az <= 360.0;  // false for NaN
      s.sat.elevation_deg = known ? el : std::nan("");
      s.sat.azimuth_deg = known ? az : std::nan("");
      if (!field(c_cn0).empty() &&
          (!parse_field(field(c_cn0), s.sat.cn0_dbhz) || !(s.sat.cn0_dbhz >= 0.0 && s.sat.cn0_dbhz <= 100.0)))
        throw fail(r, c_cn0, "is not a C/N0 in [0, 100] dB-Hz");
      if (!known && std::isfinite(s.sat.cn0_dbhz)) ++without_geometry;
      for (const auto& o : epoch)
        if (o.sat.id == s.sat.id)
          throw fail(r, c_id, "appears twice in the epoch at time_s " + fmt(time) + " (also line " + std::to_string(t.lines[o.row]) + ")");
      epoch.push_back(s);
    }
    // Labels by time.
    std::vector<std::pair<double, int>> labels;
    if (!labels_path.empty()) {
      const Table l = read_table(labels_path);
      const int lt = l.column("time_s"), ll = l.column("label");
      if (lt < 0 || ll < 0) throw InputError(labels_path + ":1: needs columns time_s and label");
      for (std::size_t r = 0; r < l.rows.size(); ++r) {
        double time = 0, label = 0;
        if (!parse_field(l.rows[r][static_cast<std::size_t>(lt)], time) || !std::isfinite(time) ||
            !parse_field(l.rows[r][static_cast<std::size_t>(ll)], label) || label != std::floor(label) || std::abs(label) > 1e9)
          throw InputError(labels_path + ":" + std::to_string(l.lines[r]) + ": time_s must be a number and label an integer");
        labels.emplace_back(time, static_cast<int>(label));
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
        if (std::isfinite(s.pdop)) {
          if (std::isfinite(pdop) && pdop != s.pdop) throw fail(s.row, c_pdop, "differs from the epoch's other pdop");
          pdop = s.pdop;
        }
        if (s.sat.id >= 0) sats.push_back(s.sat);
      }
      feat::GnssSceneFeatures f;
      const auto status = extractor.push({time, sats, pdop}, f);
      if (status != feat::GnssFeatureStatus::ok)
        throw InputError(sats_path + ":" + std::to_string(t.lines[rows.front().row]) + ": epoch at time_s " + fmt(time) + ": " +
                         std::string(feat::describe(status)));
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

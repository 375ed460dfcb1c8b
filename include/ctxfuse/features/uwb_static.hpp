// Reader for static UWB ranging recordings laid out as
//   <root>/{LOS,NLOS}/height_<h>cm/<d>m.csv
// (the Hanyang outdoor UWB dataset): true distance d in the file name, antenna height h in the
// folder name, one DW1000 range per CSV row with columns found by header name: `Distance` [m],
// `RSSI(dBm)`, `RSSI_fp(dBm)` (first-path power).
//
// - The recordings end with a summary block ("Distance Mean,10.07", ...): the first row whose
//   first field is not a number ends the data; the rest of the file is ignored.
// - Rows whose RSSI or first-path RSSI is -inf/inf/nan (the chip reports -inf when a power
//   computation fails) are skipped and counted, not treated as errors.
// - Anything else that does not parse (wrong number of fields, a non-number in a used column,
//   a negative or absurd distance) throws UwbDataError naming file, line and column.
#pragma once

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace ctxfuse::features {

class UwbDataError : public std::runtime_error {
 public:
  UwbDataError(const std::string& file, std::size_t line, const std::string& field, const std::string& what)
      : std::runtime_error(message(file, line, field, what)) {}

 private:
  // Appended piece by piece: g++ 12 warns (-Wrestrict, a false positive) on the inlined
  // `"literal" + std::string&&` that a single concatenation expression produces.
  static std::string message(const std::string& file, std::size_t line, const std::string& field, const std::string& what) {
    std::string m = file;
    if (line > 0) m.append(":").append(std::to_string(line));
    if (!field.empty()) m.append(": column '").append(field).append("'");
    return m.append(": ").append(what);
  }
};

struct UwbStaticRange {
  double true_distance_m = 0.0;
  double measured_distance_m = 0.0;
  double rssi_dbm = 0.0;
  double first_path_rssi_dbm = 0.0;
  bool nlos = false;
  double height_cm = 0.0;
  std::size_t file_index = 0;  // ranges of one recording share it (in reading order)

  double range_residual_m() const { return measured_distance_m - true_distance_m; }
  double rssi_minus_first_path_db() const { return rssi_dbm - first_path_rssi_dbm; }
};

struct UwbStaticReadStats {
  std::size_t files = 0;
  std::size_t ranges = 0;
  std::size_t skipped_non_finite_power = 0;
};

namespace detail {

inline std::vector<std::string_view> split_csv_line(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    std::string_view f = line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    while (!f.empty() && (f.front() == ' ' || f.front() == '\t')) f.remove_prefix(1);
    while (!f.empty() && (f.back() == ' ' || f.back() == '\t' || f.back() == '\r')) f.remove_suffix(1);
    out.push_back(f);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return out;
}

/// Whole-field double parse accepting inf/-inf/nan spellings (from_chars does).
inline bool parse_field(std::string_view s, double& out) {
  if (s.empty()) return false;
  if (s.front() == '+') s.remove_prefix(1);
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc{} && p == s.data() + s.size();
}

/// Leading number of a name such as "58m.csv" or "height_62.5cm"; NaN when absent.
inline double number_in_name(std::string_view name, std::string_view prefix, std::string_view suffix) {
  if (name.size() <= prefix.size() + suffix.size() || name.substr(0, prefix.size()) != prefix ||
      name.substr(name.size() - suffix.size()) != suffix)
    return std::nan("");
  double v = 0.0;
  const auto body = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
  return parse_field(body, v) && std::isfinite(v) ? v : std::nan("");
}

}  // namespace detail

/// Reads one recording. `true_distance_m`, `nlos` and `height_cm` label every range.
inline std::vector<UwbStaticRange> read_uwb_static_file(const std::filesystem::path& path, double true_distance_m,
                                                        bool nlos, double height_cm, UwbStaticReadStats& stats) {
  const std::string file = path.string();
  std::ifstream in(path);
  if (!in) throw UwbDataError(file, 0, "", "cannot open file");
  std::string line;
  std::size_t line_no = 0;
  if (!std::getline(in, line)) throw UwbDataError(file, 1, "", "empty file (no header)");
  ++line_no;
  const auto header = detail::split_csv_line(line);
  auto column = [&](std::string_view name) -> std::size_t {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) throw UwbDataError(file, 1, std::string(name), "column missing from the header");
    return static_cast<std::size_t>(it - header.begin());
  };
  const std::size_t c_dist = column("Distance"), c_rssi = column("RSSI(dBm)"), c_fp = column("RSSI_fp(dBm)");
  const std::vector<std::string> names(header.begin(), header.end());  // header views die with `line`
  std::vector<UwbStaticRange> out;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line == "\r") continue;
    const auto fields = detail::split_csv_line(line);
    double first = 0.0;
    if (!detail::parse_field(fields[0], first)) break;  // summary block
    if (fields.size() != names.size())
      throw UwbDataError(file, line_no, "", std::to_string(fields.size()) + " fields, header has " +
                                                std::to_string(names.size()));
    UwbStaticRange r;
    r.true_distance_m = true_distance_m;
    r.nlos = nlos;
    r.height_cm = height_cm;
    r.file_index = stats.files;
    auto get = [&](std::size_t c, double& v) {
      if (!detail::parse_field(fields[c], v))
        throw UwbDataError(file, line_no, names[c], "'" + std::string(fields[c]) + "' is not a number");
    };
    get(c_dist, r.measured_distance_m);
    get(c_rssi, r.rssi_dbm);
    get(c_fp, r.first_path_rssi_dbm);
    if (!std::isfinite(r.measured_distance_m) || r.measured_distance_m < 0.0 || r.measured_distance_m > 1000.0)
      throw UwbDataError(file, line_no, names[c_dist],
                         "distance " + std::string(fields[c_dist]) + " outside [0, 1000] m");
    if (!std::isfinite(r.rssi_dbm) || !std::isfinite(r.first_path_rssi_dbm)) {
      ++stats.skipped_non_finite_power;
      continue;
    }
    out.push_back(r);
  }
  ++stats.files;
  stats.ranges += out.size();
  return out;
}

/// Reads every <root>/{LOS,NLOS}/height_<h>cm/<d>m.csv, optionally only some heights (empty =
/// all; a height matches within 0.01 cm). Files are visited in sorted path order. Throws
/// UwbDataError on a malformed file or a root without LOS/ and NLOS/.
inline std::vector<UwbStaticRange> read_uwb_static_dataset(const std::filesystem::path& root,
                                                           const std::vector<double>& heights_cm,
                                                           UwbStaticReadStats& stats) {
  namespace fs = std::filesystem;
  std::vector<UwbStaticRange> out;
  for (const bool nlos : {false, true}) {
    const fs::path dir = root / (nlos ? "NLOS" : "LOS");
    if (!fs::is_directory(dir)) throw UwbDataError(dir.string(), 0, "", "folder missing");
    std::vector<fs::path> files;
    for (const auto& h : fs::directory_iterator(dir)) {
      if (!h.is_directory()) continue;
      const double height = detail::number_in_name(h.path().filename().string(), "height_", "cm");
      if (std::isnan(height)) continue;
      if (!heights_cm.empty() &&
          std::none_of(heights_cm.begin(), heights_cm.end(), [&](double x) { return std::abs(x - height) < 0.01; }))
        continue;
      for (const auto& f : fs::directory_iterator(h.path()))
        if (f.is_regular_file() && f.path().extension() == ".csv") files.push_back(f.path());
    }
    std::sort(files.begin(), files.end());
    for (const auto& f : files) {
      const double d = detail::number_in_name(f.filename().string(), "", "m.csv");
      if (std::isnan(d) || d <= 0.0) throw UwbDataError(f.string(), 0, "", "file name does not give the distance as <d>m.csv");
      const double height = detail::number_in_name(f.parent_path().filename().string(), "height_", "cm");
      auto ranges = read_uwb_static_file(f, d, nlos, height, stats);
      out.insert(out.end(), ranges.begin(), ranges.end());
    }
  }
  return out;
}

}  // namespace ctxfuse::features

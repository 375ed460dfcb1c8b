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
// - A last line without a newline, before the summary block, is a cut line: skipped and
//   counted (a cut number still parses, "-79." for "-79.5").
// - Anything else that does not parse (wrong number of fields, a non-number in a used column,
//   a negative or absurd distance) throws io::ParseError (alias UwbDataError) naming file,
//   line and column (file:line:column: column 'name': ...).
#pragma once

#include <ctxfuse/io/text.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace ctxfuse::io {

/// Kept for the users of this reader's first version: its errors are the io readers' ones.
using UwbDataError = io::ParseError;

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
  std::size_t skipped_partial_last_lines = 0;  // one at most per file
};

namespace detail {

/// Leading number of a name such as "58m.csv" or "height_62.5cm"; NaN when absent.
inline double number_in_name(std::string_view name, std::string_view prefix, std::string_view suffix) {
  if (name.size() <= prefix.size() + suffix.size() || name.substr(0, prefix.size()) != prefix ||
      name.substr(name.size() - suffix.size()) != suffix)
    return std::nan("");
  double v = 0.0;
  const auto body = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
  return io::parse_real(body, v) == io::NumberError::none ? v : std::nan("");
}

}  // namespace detail

/// Reads one recording. `true_distance_m`, `nlos` and `height_cm` label every range.
inline std::vector<UwbStaticRange> read_uwb_static_file(const std::filesystem::path& path, double true_distance_m,
                                                        bool nlos, double height_cm, UwbStaticReadStats& stats) {
  io::TextFile file(path);
  const io::Header header = io::read_header(file, io::Separator::comma);
  const std::size_t c_dist = io::require_column(file, header, "Distance"),
                    c_rssi = io::require_column(file, header, "RSSI(dBm)"),
                    c_fp = io::require_column(file, header, "RSSI_fp(dBm)");
  io::Fields f(file.name(), &header);
  io::RealRules power;  // the chip writes -inf when a power estimate fails
  power.allow_non_finite = true;
  std::vector<UwbStaticRange> out;
  while (io::next_fields(file, f, io::Separator::comma)) {
    double first = 0.0;
    if (io::parse_real(f[0], first, power) != io::NumberError::none) break;  // summary block
    if (!file.ended_by_newline()) {
      ++stats.skipped_partial_last_lines;
      break;
    }
    f.expect_count(header.size());
    UwbStaticRange r;
    r.true_distance_m = true_distance_m;
    r.nlos = nlos;
    r.height_cm = height_cm;
    r.file_index = stats.files;
    r.measured_distance_m = f.real_in(c_dist, 0.0, 1000.0);
    r.rssi_dbm = f.real(c_rssi, power);
    r.first_path_rssi_dbm = f.real(c_fp, power);
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
    if (!fs::is_directory(dir)) throw io::ParseError(dir.string(), 0, 0, "", "folder missing");
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
      if (std::isnan(d) || d <= 0.0)
        throw io::ParseError(f.string(), 0, 0, "", "file name does not give the distance as <d>m.csv");
      const double height = detail::number_in_name(f.parent_path().filename().string(), "height_", "cm");
      auto ranges = read_uwb_static_file(f, d, nlos, height, stats);
      out.insert(out.end(), ranges.begin(), ranges.end());
    }
  }
  return out;
}

}  // namespace ctxfuse::io

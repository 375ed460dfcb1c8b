// Reader of one dynamic case of the Hanyang outdoor UWB dataset
// (Dynamic_measurements/{LOS,NLOS}/Trajectory_*/Case_*/): the per-anchor range files A<id>.csv
// merged into one time-ordered stream of messages::UwbRange, and the case's reference trajectory
// (trajectory.csv), which is truth and so is read by its own function into its own type.
//
// - Range files are rosbag exports: "%time,field.stamp,field.id,field.x,...". Columns are
//   found by name with the "%" and "field." decorations dropped, so a re-export with plain
//   names reads the same. The time used is the bag's record time `%time` [ns].
// - Every row of A<id>.csv must carry anchor id <id>: a file renamed or mixed up would
//   otherwise silently move an anchor.
// - The DW1000 reports -inf power when its estimate fails; such rows keep their range (the
//   two-way time of flight is unaffected) with NaN RSSI, and are counted.
// - Times must strictly increase within each file; the merge orders by time, then anchor id.
// write_hanyang_case writes ranges and a reference in the same layout (simulated cases).
#pragma once

#include <ctxfuse/messages/sensors.hpp>
#include <ctxfuse/io/text.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ctxfuse::io {

struct HanyangRange {
  std::int64_t t_ns = 0;  // exact stamp; range.t is the same in seconds (rounded to ~0.2 us)
  messages::UwbRange range;
};

struct HanyangUwbCase {
  std::vector<HanyangRange> ranges;  // all anchors, time order
  std::map<int, std::size_t> ranges_per_anchor;
  std::size_t non_finite_rssi = 0;  // rows kept with NaN rssi and/or rssi_fp
  std::size_t skipped_partial_last_lines = 0;  // a file's last line without its newline (cut short)
  std::vector<std::string> files;

  std::vector<messages::UwbRange> uwb_ranges() const {
    std::vector<messages::UwbRange> out;
    out.reserve(ranges.size());
    for (const auto& r : ranges) out.push_back(r.range);
    return out;
  }
};

/// One reference sample of the case (truth: for scoring only, never a filter input).
struct HanyangReferencePose {
  double t = 0.0;  // seconds, same clock as the ranges
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double heading_deg = 0.0;  // unwrapped as recorded: it runs past +-360 on a looped track
};

namespace detail {

inline std::string_view bare_column_name(std::string_view s) {
  if (!s.empty() && s.front() == '%') s.remove_prefix(1);
  if (s.substr(0, 6) == "field.") s.remove_prefix(6);
  return s;
}

/// Reads the header line of `file` and returns the 0-based index of each wanted name.
template <std::size_t N>
std::array<std::size_t, N> header_columns(TextFile& file, Header& header, const std::array<std::string_view, N>& wanted) {
  header = read_header(file, Separator::comma);
  std::array<std::size_t, N> idx{};
  for (std::size_t k = 0; k < N; ++k) {
    std::size_t i = 0;
    while (i < header.size() && bare_column_name(header.name(i)) != wanted[k]) ++i;
    if (i == header.size()) file.fail(cat("header has no column ", quote(wanted[k])));
    idx[k] = i;
  }
  return idx;
}

inline double seconds_of(std::int64_t t_ns) {
  // Split first so that the sub-second part keeps its nanoseconds before the sum rounds.
  return static_cast<double>(t_ns / 1'000'000'000) + static_cast<double>(t_ns % 1'000'000'000) * 1e-9;
}

/// "A12.csv" -> 12; -1 for any other name.
inline int anchor_of_file_name(const std::string& name) {
  if (name.size() < 6 || name.front() != 'A' || name.substr(name.size() - 4) != ".csv") return -1;
  int id = -1;
  return parse_integer(std::string_view(name).substr(1, name.size() - 5), id, 0, 1'000'000) == NumberError::none ? id : -1;
}

inline void read_hanyang_anchor_file(const std::filesystem::path& path, int anchor, HanyangUwbCase& out) {
  TextFile file(path);
  Header header;
  const auto c = header_columns<8>(file, header, {"time", "id", "x", "y", "z", "distanceFromTag", "rssi", "rssi_fp"});
  Fields f(file.name(), &header);
  RealRules power;
  power.allow_non_finite = true;
  std::int64_t previous = 0;
  std::size_t previous_line = 0, count = 0;
  while (next_fields(file, f, Separator::comma)) {
    // A last line without its newline was cut short (a number cut short still parses).
    if (!file.ended_by_newline()) {
      ++out.skipped_partial_last_lines;
      break;
    }
    f.expect_count(header.size());
    HanyangRange r;
    r.t_ns = f.integer<std::int64_t>(c[0], 0, std::numeric_limits<std::int64_t>::max());
    if (count > 0 && r.t_ns <= previous)
      f.fail(c[0], cat("time ", r.t_ns, " is not after the previous row's (line ", previous_line, ")"));
    r.range.t = seconds_of(r.t_ns);
    r.range.anchor_id = f.integer<int>(c[1], 0, 1'000'000);
    if (r.range.anchor_id != anchor)
      f.fail(c[1], cat("anchor id ", r.range.anchor_id, " in the file of anchor ", anchor));
    for (int k = 0; k < 3; ++k) r.range.anchor_position[k] = f.real_in(c[2 + static_cast<std::size_t>(k)], -1e5, 1e5);
    r.range.range_m = f.real_in(c[5], 0.0, 1000.0);
    const double rssi = f.real_in(c[6], -200.0, 50.0, power), fp = f.real_in(c[7], -200.0, 50.0, power);
    r.range.rssi_dbm = std::isfinite(rssi) ? rssi : messages::kUnknown;
    r.range.rssi_first_path_dbm = std::isfinite(fp) ? fp : messages::kUnknown;
    out.non_finite_rssi += !std::isfinite(rssi) || !std::isfinite(fp);
    previous = r.t_ns;
    previous_line = file.line_number();
    out.ranges.push_back(r);
    ++count;
  }
  out.ranges_per_anchor[anchor] += count;
  out.files.push_back(file.name());
}

}  // namespace detail

/// Reads every A<id>.csv of a case folder (at least one) and merges them in time order.
inline HanyangUwbCase read_hanyang_uwb(const std::filesystem::path& case_dir) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(case_dir)) throw ParseError(case_dir.string(), 0, 0, "", "not a folder");
  std::vector<std::pair<int, fs::path>> files;
  for (const auto& e : fs::directory_iterator(case_dir))
    if (const int id = detail::anchor_of_file_name(e.path().filename().string()); e.is_regular_file() && id >= 0)
      files.emplace_back(id, e.path());
  if (files.empty()) throw ParseError(case_dir.string(), 0, 0, "", "no anchor range file A<id>.csv");
  std::sort(files.begin(), files.end());
  HanyangUwbCase out;
  for (const auto& [id, path] : files) detail::read_hanyang_anchor_file(path, id, out);
  std::stable_sort(out.ranges.begin(), out.ranges.end(), [](const HanyangRange& a, const HanyangRange& b) {
    return a.t_ns != b.t_ns ? a.t_ns < b.t_ns : a.range.anchor_id < b.range.anchor_id;
  });
  return out;
}

/// Reads a Hanyang reference file (trajectory.csv: timestamp [ns, written as a float], x, y,
/// z [m], heading [deg]): the reference, on the ranges' clock.
inline std::vector<HanyangReferencePose> read_hanyang_reference_file(const std::filesystem::path& file_path) {
  TextFile file(file_path);
  Header header;
  const auto c = detail::header_columns<5>(file, header, {"timestamp", "x", "y", "z", "heading_degrees"});
  Fields f(file.name(), &header);
  std::vector<HanyangReferencePose> out;
  std::size_t previous_line = 0;
  while (next_fields(file, f, Separator::comma)) {
    if (!file.ended_by_newline()) break;  // a last line cut short (a number cut short still parses)
    f.expect_count(header.size());
    HanyangReferencePose p;
    p.t = f.real_in(c[0], 0.0, 1e19) * 1e-9;
    if (!out.empty() && !(p.t > out.back().t))
      f.fail(c[0], cat("time is not after the previous row's (line ", previous_line, ")"));
    for (int k = 0; k < 3; ++k) p.position[k] = f.real_in(c[1 + static_cast<std::size_t>(k)], -1e5, 1e5);
    p.heading_deg = f.real_in(c[4], -1e6, 1e6);
    previous_line = file.line_number();
    out.push_back(p);
  }
  return out;
}

/// The case's trajectory.csv (read_hanyang_reference_file).
inline std::vector<HanyangReferencePose> read_hanyang_reference(const std::filesystem::path& case_dir) {
  return read_hanyang_reference_file(case_dir / "trajectory.csv");
}

/// Writes a case folder in the dataset's layout, so that read_hanyang_uwb and
/// read_hanyang_reference read it back: one A<id>.csv per anchor (the rosbag export's columns
/// %time, field.stamp (the same stamp), field.id, field.x/y/z, field.distanceFromTag,
/// field.rssi, field.rssi_fp; unknown powers as -inf, as the DW1000 reports them) and, when
/// `reference` is not empty, trajectory.csv. Stamps are written in ns (t rounded to the ns).
/// Creates `dir` if needed. Throws std::invalid_argument for ranges the reader would refuse
/// (non-finite or negative times, ranges outside [0, 1000] m, times that do not increase within
/// an anchor, an anchor whose position changes) before writing anything, std::runtime_error
/// when a file cannot be written.
inline void write_hanyang_case(const std::filesystem::path& dir, std::span<const messages::UwbRange> ranges,
                               std::span<const HanyangReferencePose> reference = {}) {
  namespace fs = std::filesystem;
  std::map<int, std::vector<const messages::UwbRange*>> by_anchor;
  for (const auto& r : ranges) {
    if (!(std::isfinite(r.t) && r.t >= 0.0 && r.t < 9.2e9)) throw std::invalid_argument(cat("write_hanyang_case: time ", r.t, " s"));
    if (!(r.range_m >= 0.0 && r.range_m <= 1000.0)) throw std::invalid_argument(cat("write_hanyang_case: range ", r.range_m, " m"));
    if (!r.anchor_position.allFinite() || (r.anchor_position.array().abs() > 1e5).any())
      throw std::invalid_argument(cat("write_hanyang_case: anchor ", r.anchor_id, " position not finite or beyond 1e5 m"));
    if (r.anchor_id < 0 || r.anchor_id > 1'000'000) throw std::invalid_argument(cat("write_hanyang_case: anchor id ", r.anchor_id));
    auto& list = by_anchor[r.anchor_id];
    if (!list.empty()) {
      if (std::llround(r.t * 1e9) <= std::llround(list.back()->t * 1e9))
        throw std::invalid_argument(cat("write_hanyang_case: anchor ", r.anchor_id, " time ", r.t, " s not after the previous one"));
      if (r.anchor_position != list.front()->anchor_position)
        throw std::invalid_argument(cat("write_hanyang_case: anchor ", r.anchor_id, " moves"));
    }
    list.push_back(&r);
  }
  for (std::size_t i = 1; i < reference.size(); ++i)
    if (!(reference[i].t > reference[i - 1].t)) throw std::invalid_argument("write_hanyang_case: reference times must increase");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir)) throw std::runtime_error("write_hanyang_case: cannot create " + dir.string());
  auto power = [](double v, char* buf, std::size_t n) {
    if (std::isfinite(v)) std::snprintf(buf, n, "%.17g", v);
    else std::snprintf(buf, n, "-inf");
  };
  char line[512], rssi[40], fp[40];
  for (const auto& [id, list] : by_anchor) {
    const fs::path path = dir / cat('A', id, ".csv");
    std::ofstream os(path);
    os << "%time,field.stamp,field.id,field.x,field.y,field.z,field.distanceFromTag,field.rssi,field.rssi_fp\n";
    for (const messages::UwbRange* r : list) {
      const long long t_ns = std::llround(r->t * 1e9);
      power(r->rssi_dbm, rssi, sizeof rssi);
      power(r->rssi_first_path_dbm, fp, sizeof fp);
      std::snprintf(line, sizeof line, "%lld,%lld,%d,%.17g,%.17g,%.17g,%.17g,%s,%s\n", t_ns, t_ns, id, r->anchor_position.x(),
                    r->anchor_position.y(), r->anchor_position.z(), r->range_m, rssi, fp);
      os << line;
    }
    if (!os.flush()) throw std::runtime_error("write_hanyang_case: cannot write " + path.string());
  }
  if (reference.empty()) return;
  const fs::path path = dir / "trajectory.csv";
  std::ofstream os(path);
  os << "timestamp,x,y,z,heading_degrees\n";
  for (const auto& p : reference) {
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g,%.17g,%.17g\n", static_cast<double>(std::llround(p.t * 1e9)), p.position.x(),
                  p.position.y(), p.position.z(), p.heading_deg);
    os << line;
  }
  if (!os.flush()) throw std::runtime_error("write_hanyang_case: cannot write " + path.string());
}

}  // namespace ctxfuse::io

// The Hanyang dataset authors' evaluation protocol (data README; their RMSD_results.txt follow
// it): the evaluated span runs from the first reference sample inside the track's start gate to
// the first later one inside its end gate; reference samples with |z| >= 0.5 m are dropped; the
// kept reference is interpolated linearly to each estimate's time in the span (held at its
// ends); 2-D RMSE over the estimates in the span. Also the readers of the authors' own result
// files (LS.csv, ESKF.csv: timestamp [ns], x, y, z; RMSD_results.txt), so that their figures are
// recomputed here and quoted from their file, never typed in.
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "ctxfuse/io/hanyang_uwb.hpp"
#include "ctxfuse/io/text.hpp"

namespace ctxfuse::eval {

/// One axis-aligned gate: x and y each compared against a bound (> or <= as flagged).
struct TrackGate {
  double x = 0.0, y = 0.0;
  bool x_above = true, y_above = true;  // x > bound (else x <= bound / x < bound as below)
  bool contains(const Eigen::Vector3d& p) const {
    return (x_above ? p.x() > x : p.x() <= x) && (y_above ? p.y() > y : p.y() <= y);
  }
};

struct HanyangSpan {
  TrackGate start, end;
  double max_abs_z = 0.5;
};

/// Trajectory A: from the first sample with x > 49.3 and y > -5 to the first later one with
/// x <= 12 and y > 3.4. Trajectory B: from x < 8.6 and y < -7 to x > 8.6 and y < -7 (both
/// strict in the authors' text; the 8.6 bound is met exactly by no float sample, so < and <=
/// agree).
inline HanyangSpan trajectory_a_span() { return {{49.3, -5.0, true, true}, {12.0, 3.4, false, true}}; }
inline HanyangSpan trajectory_b_span() { return {{8.6, -7.0, false, false}, {8.6, -7.0, true, false}}; }

struct TimedPoint2 {
  double t = 0.0;
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
};

struct ProtocolRmse {
  double rmse_2d = std::nan("");
  std::size_t scored = 0;  // estimates inside the span
  double t_begin = std::nan(""), t_end = std::nan("");
};

/// The authors' 2-D RMSE of `estimates` (time order) against `reference`; with `errors`, also
/// each estimate's own 2-D error, the numbers the RMSE aggregates (NaN outside the span). Throws
/// std::invalid_argument when the span's gates are never passed or no reference sample is kept.
inline ProtocolRmse hanyang_rmse_2d(std::span<const TimedPoint2> estimates, std::span<const io::HanyangReferencePose> reference,
                                    const HanyangSpan& span, std::vector<double>* errors = nullptr) {
  std::size_t i0 = 0;
  while (i0 < reference.size() && !span.start.contains(reference[i0].position)) ++i0;
  std::size_t i1 = i0 + 1;
  while (i1 < reference.size() && !span.end.contains(reference[i1].position)) ++i1;
  if (i0 >= reference.size() || i1 >= reference.size())
    throw std::invalid_argument("hanyang_rmse_2d: the reference never passes the span's start and end gates");
  std::vector<io::HanyangReferencePose> kept;
  for (std::size_t i = i0; i <= i1; ++i)
    if (std::abs(reference[i].position.z()) < span.max_abs_z) kept.push_back(reference[i]);
  if (kept.empty()) throw std::invalid_argument("hanyang_rmse_2d: no reference sample in the span has |z| < max_abs_z");
  ProtocolRmse out;
  out.t_begin = reference[i0].t;
  out.t_end = reference[i1].t;
  double sq = 0.0;
  std::size_t j = 0;
  if (errors) errors->assign(estimates.size(), std::nan(""));
  for (std::size_t k = 0; k < estimates.size(); ++k) {
    const TimedPoint2& e = estimates[k];
    if (e.t < out.t_begin || e.t > out.t_end) continue;
    Eigen::Vector2d ref;
    if (e.t <= kept.front().t) {
      ref = kept.front().position.head<2>();
    } else if (e.t >= kept.back().t) {
      ref = kept.back().position.head<2>();
    } else {
      while (kept[j + 1].t < e.t) ++j;  // estimates in time order: j only moves forward
      const double a = (e.t - kept[j].t) / (kept[j + 1].t - kept[j].t);
      ref = (1.0 - a) * kept[j].position.head<2>() + a * kept[j + 1].position.head<2>();
    }
    const double e2 = (e.p - ref).squaredNorm();
    if (errors) (*errors)[k] = std::sqrt(e2);
    sq += e2;
    ++out.scored;
  }
  if (out.scored > 0) out.rmse_2d = std::sqrt(sq / static_cast<double>(out.scored));
  return out;
}

/// The authors' estimates (LS.csv / ESKF.csv of a case): timestamp [ns], x, y, z [m]; stamps
/// must not decrease.
inline std::vector<TimedPoint2> read_hanyang_estimates(const std::filesystem::path& file_path) {
  io::TextFile file(file_path);
  io::Header header;
  const auto c = io::detail::header_columns<3>(file, header, {"timestamp", "x", "y"});
  io::Fields f(file.name(), &header);
  std::vector<TimedPoint2> out;
  while (io::next_fields(file, f, io::Separator::comma)) {
    f.expect_count(header.size());
    TimedPoint2 p;
    p.t = io::detail::seconds_of(f.integer<std::int64_t>(c[0], 0, std::numeric_limits<std::int64_t>::max()));
    p.p = {f.real_in(c[1], -1e5, 1e5), f.real_in(c[2], -1e5, 1e5)};
    // Their ESKF files repeat their last row a few times (equal stamps): kept, as they score them.
    if (!out.empty() && p.t < out.back().t) f.fail(c[0], "time is before the previous row's");
    out.push_back(p);
  }
  return out;
}

/// RMSD_results.txt: lines "NAME: value [m]" (e.g. "LS RMSE_2d: 0.9775"), name -> value.
inline std::map<std::string, double> read_hanyang_rmsd(const std::filesystem::path& file_path) {
  io::TextFile file(file_path);
  std::map<std::string, double> out;
  std::string_view line;
  while (file.next(line)) {
    const auto colon = line.find(':');
    if (colon == std::string_view::npos) continue;
    std::string_view value = line.substr(colon + 1);
    while (!value.empty() && value.front() == ' ') value.remove_prefix(1);
    if (const auto space = value.find(' '); space != std::string_view::npos) value = value.substr(0, space);
    double v = 0.0;
    if (io::parse_real(value, v) != io::NumberError::none || !std::isfinite(v))
      file.fail(io::cat("no number after the colon: ", io::quote(line)));
    out[std::string(line.substr(0, colon))] = v;
  }
  return out;
}

}  // namespace ctxfuse::eval

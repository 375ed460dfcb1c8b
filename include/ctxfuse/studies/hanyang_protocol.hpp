// The Hanyang dataset authors' evaluation protocol (data README; their RMSD_results.txt follow
// it): the evaluated span runs from the first reference sample inside the track's start gate to
// the first later one inside its end gate; reference samples with |z| >= 0.5 m are dropped; the
// kept reference is interpolated linearly to each estimate's time in the span (held at its
// ends); 2-D RMSE over the estimates in the span. Both spans of the dataset README (trajectory
// A and B), custom spans read from text (parse_hanyang_span), and the plain whole-run 2-D RMSE
// for a reference no span fits; choose_protocol picks one for a reference and says why a span
// asked for does not fit (find_span). Also the readers of trajectory CSVs (ours, time_ns; the
// authors' LS.csv, ESKF.csv: timestamp [ns], x, y, z) and of RMSD_results.txt, so that their
// figures are recomputed here and quoted from their file, never typed in.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <initializer_list>
#include <map>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "ctxfuse/io/hanyang_uwb.hpp"
#include "ctxfuse/io/text.hpp"

namespace ctxfuse::studies {

/// One bound of a gate on one axis: none, or the coordinate compared with `value`.
struct AxisBound {
  enum class Op : std::uint8_t { none, gt, ge, lt, le };
  Op op = Op::none;
  double value = 0.0;
  bool contains(double v) const {
    switch (op) {
      case Op::gt: return v > value;
      case Op::ge: return v >= value;
      case Op::lt: return v < value;
      case Op::le: return v <= value;
      case Op::none: return true;
    }
    return true;
  }
};

/// One axis-aligned gate: the conditions on x and on y both hold.
struct TrackGate {
  AxisBound x, y;
  bool contains(const Eigen::Vector3d& p) const { return x.contains(p.x()) && y.contains(p.y()); }
};

struct HanyangSpan {
  TrackGate start, end;
  double max_abs_z = 0.5;
};

/// Trajectory A: from the first sample with x > 49.3 and y > -5 to the first later one with
/// x <= 12 and y > 3.4. Trajectory B: from x < 8.6 and y < -7 to x > 8.6 and y < -7 (as in the
/// authors' text).
inline HanyangSpan trajectory_a_span() {
  using O = AxisBound::Op;
  return {{{O::gt, 49.3}, {O::gt, -5.0}}, {{O::le, 12.0}, {O::gt, 3.4}}};
}
inline HanyangSpan trajectory_b_span() {
  using O = AxisBound::Op;
  return {{{O::lt, 8.6}, {O::lt, -7.0}}, {{O::gt, 8.6}, {O::lt, -7.0}}};
}

/// "x>49.3,y>-5": the gate in the form parse_track_gate reads.
inline std::string describe(const TrackGate& g) {
  std::string out;
  auto one = [&](char axis, const AxisBound& b) {
    static constexpr const char* ops[] = {"", ">", ">=", "<", "<="};
    if (b.op == AxisBound::Op::none) return;
    if (!out.empty()) out += ',';
    out += io::cat(axis, std::string_view(ops[static_cast<int>(b.op)]), b.value);
  };
  one('x', g.x);
  one('y', g.y);
  return out.empty() ? "anywhere" : out;
}

/// Reads a gate "x>49.3,y>-5" (comma-separated conditions on x and/or y with >, >=, <, <=;
/// each axis at most once, at least one axis). Returns "" or what is wrong.
inline std::string parse_track_gate(std::string_view text, TrackGate& out) {
  out = TrackGate{};
  if (text.empty()) return "empty gate";
  while (!text.empty()) {
    const auto comma = text.find(',');
    std::string_view cond = text.substr(0, comma);
    text = comma == std::string_view::npos ? std::string_view() : text.substr(comma + 1);
    if (comma != std::string_view::npos && text.empty()) return "a comma ends the gate";
    cond = io::trim(cond);
    if (cond.size() < 3 || (cond[0] != 'x' && cond[0] != 'y'))
      return "condition '" + std::string(cond) + "' does not start with x or y";
    AxisBound& b = cond[0] == 'x' ? out.x : out.y;
    if (b.op != AxisBound::Op::none) return std::string("axis ") + cond[0] + " given twice";
    std::string_view rest = io::trim(cond.substr(1));
    if (rest.starts_with(">=")) b.op = AxisBound::Op::ge, rest.remove_prefix(2);
    else if (rest.starts_with("<=")) b.op = AxisBound::Op::le, rest.remove_prefix(2);
    else if (rest.starts_with(">")) b.op = AxisBound::Op::gt, rest.remove_prefix(1);
    else if (rest.starts_with("<")) b.op = AxisBound::Op::lt, rest.remove_prefix(1);
    else return "condition '" + std::string(cond) + "' has no comparison (>, >=, <, <=)";
    if (io::parse_real(io::trim(rest), b.value) != io::NumberError::none || !std::isfinite(b.value))
      return "condition '" + std::string(cond) + "' has no finite number after its comparison";
  }
  return {};
}

/// Reads a custom span "START/END", each a gate for parse_track_gate, e.g. the trajectory A
/// span as "x>49.3,y>-5/x<=12,y>3.4". Returns "" or what is wrong.
inline std::string parse_hanyang_span(std::string_view text, HanyangSpan& out) {
  const auto slash = text.find('/');
  if (slash == std::string_view::npos || text.find('/', slash + 1) != std::string_view::npos)
    return "a span is START/END (two gates separated by one '/'), e.g. x>49.3,y>-5/x<=12,y>3.4";
  out = HanyangSpan{};
  if (std::string e = parse_track_gate(text.substr(0, slash), out.start); !e.empty()) return "start gate: " + e;
  if (std::string e = parse_track_gate(text.substr(slash + 1), out.end); !e.empty()) return "end gate: " + e;
  return {};
}

/// Where the span lies on `reference`: indices of its first sample in the start gate and of the
/// first later one in the end gate. `problem` says why there is none ("" when there is).
struct SpanBounds {
  std::size_t begin = 0, end = 0;
  std::string problem;
};

inline SpanBounds find_span(std::span<const io::HanyangReferencePose> reference, const HanyangSpan& span) {
  SpanBounds b;
  std::size_t i0 = 0;
  while (i0 < reference.size() && !span.start.contains(reference[i0].position)) ++i0;
  if (i0 >= reference.size()) {
    b.problem = "the reference never enters the start gate (" + describe(span.start) + ")";
    return b;
  }
  std::size_t i1 = i0 + 1;
  while (i1 < reference.size() && !span.end.contains(reference[i1].position)) ++i1;
  if (i1 >= reference.size()) {
    b.problem = "the reference never reaches the end gate (" + describe(span.end) + ") after the start gate (" +
                describe(span.start) + ")";
    return b;
  }
  bool kept = false;
  for (std::size_t i = i0; i <= i1 && !kept; ++i) kept = std::abs(reference[i].position.z()) < span.max_abs_z;
  if (!kept) {
    b.problem = "no reference sample in the span has |z| < " + io::cat(span.max_abs_z) + " m";
    return b;
  }
  b.begin = i0;
  b.end = i1;
  return b;
}

struct TimedPoint2 {
  double t = 0.0;
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
};

struct ProtocolRmse {
  double rmse_2d = std::nan("");
  std::size_t scored = 0;  // estimates inside the span
  double t_begin = std::nan(""), t_end = std::nan("");
};

namespace detail {

/// 2-D RMSE of the estimates with times in [out.t_begin, out.t_end] against `ref` (at least one
/// sample, time order), interpolated linearly to each estimate's time and held at its ends;
/// with `errors`, each estimate's error (NaN where not scored).
inline void accumulate_rmse_2d(std::span<const TimedPoint2> estimates, std::span<const io::HanyangReferencePose> ref,
                               ProtocolRmse& out, std::vector<double>* errors) {
  if (errors) errors->assign(estimates.size(), std::nan(""));
  double sq = 0.0;
  std::size_t j = 0;
  for (std::size_t k = 0; k < estimates.size(); ++k) {
    const TimedPoint2& e = estimates[k];
    if (!(e.t >= out.t_begin && e.t <= out.t_end)) continue;
    Eigen::Vector2d r;
    if (e.t <= ref.front().t) {
      r = ref.front().position.head<2>();
    } else if (e.t >= ref.back().t) {
      r = ref.back().position.head<2>();
    } else {
      if (k > 0 && e.t < estimates[k - 1].t) j = 0;  // out of time order: search again
      while (ref[j + 1].t < e.t) ++j;
      const double a = (e.t - ref[j].t) / (ref[j + 1].t - ref[j].t);
      r = (1.0 - a) * ref[j].position.head<2>() + a * ref[j + 1].position.head<2>();
    }
    const double e2 = (e.p - r).squaredNorm();
    if (errors) (*errors)[k] = std::sqrt(e2);
    sq += e2;
    ++out.scored;
  }
  if (out.scored > 0) out.rmse_2d = std::sqrt(sq / static_cast<double>(out.scored));
}

}  // namespace detail

/// The authors' 2-D RMSE of `estimates` (time order) against `reference`; with `errors`, also
/// each estimate's own 2-D error, the numbers the RMSE aggregates (NaN outside the span). Throws
/// std::invalid_argument naming find_span's problem when the reference does not fit the span.
inline ProtocolRmse hanyang_rmse_2d(std::span<const TimedPoint2> estimates, std::span<const io::HanyangReferencePose> reference,
                                    const HanyangSpan& span, std::vector<double>* errors = nullptr) {
  const SpanBounds bounds = find_span(reference, span);
  if (!bounds.problem.empty()) throw std::invalid_argument("hanyang_rmse_2d: " + bounds.problem);
  const std::size_t i0 = bounds.begin, i1 = bounds.end;
  std::vector<io::HanyangReferencePose> kept;
  for (std::size_t i = i0; i <= i1; ++i)
    if (std::abs(reference[i].position.z()) < span.max_abs_z) kept.push_back(reference[i]);
  ProtocolRmse out;
  out.t_begin = reference[i0].t;
  out.t_end = reference[i1].t;
  detail::accumulate_rmse_2d(estimates, kept, out, errors);
  return out;
}

/// Plain 2-D RMSE over the whole run, for a reference no protocol applies to: every reference
/// sample kept, interpolated linearly to each estimate's time; estimates outside the
/// reference's time span are not scored. `errors` as for hanyang_rmse_2d. Throws
/// std::invalid_argument when the reference has fewer than two samples.
inline ProtocolRmse plain_rmse_2d(std::span<const TimedPoint2> estimates, std::span<const io::HanyangReferencePose> reference,
                                  std::vector<double>* errors = nullptr) {
  if (reference.size() < 2) throw std::invalid_argument("plain_rmse_2d: the reference needs at least two samples");
  ProtocolRmse out;
  out.t_begin = reference.front().t;
  out.t_end = reference.back().t;
  detail::accumulate_rmse_2d(estimates, reference, out, errors);
  return out;
}

/// How a run is scored: the authors' protocol on a span, or the plain whole-run error.
struct ScoringProtocol {
  std::string name;  // "trajectory_a", "trajectory_b", "custom" or "whole_run"
  std::optional<HanyangSpan> span;  // empty: plain_rmse_2d
  std::string warning;  // why the protocol asked for was not used ("" when it was)
};

/// The protocol for `choice` on `reference`: "a", "b" (the dataset's two spans), "auto" (the
/// first of A, B whose gates the reference passes; whole run when none does), "none" (whole
/// run), or a custom span START/END (parse_hanyang_span). A named span the reference does not
/// fit falls back to the whole run with a warning naming why. Throws std::invalid_argument for
/// a choice that is none of these.
inline ScoringProtocol choose_protocol(std::string_view choice, std::span<const io::HanyangReferencePose> reference) {
  ScoringProtocol p;
  auto fits = [&](const char* name, const HanyangSpan& span) {
    const SpanBounds b = find_span(reference, span);
    if (!b.problem.empty()) return b.problem;
    p.name = name;
    p.span = span;
    return std::string();
  };
  if (choice == "none") {
    p.name = "whole_run";
    return p;
  }
  if (choice == "auto") {
    const std::string a = fits("trajectory_a", trajectory_a_span());
    if (a.empty()) return p;
    const std::string b = fits("trajectory_b", trajectory_b_span());
    if (b.empty()) return p;
    p.name = "whole_run";
    p.warning = "span auto: neither of the dataset's spans fits the reference (trajectory A: " + a + "; trajectory B: " + b +
                "): scored over the whole run";
    return p;
  }
  HanyangSpan span;
  const char* name = "custom";
  if (choice == "a") {
    span = trajectory_a_span();
    name = "trajectory_a";
  } else if (choice == "b") {
    span = trajectory_b_span();
    name = "trajectory_b";
  } else if (const std::string e = parse_hanyang_span(choice, span); !e.empty()) {
    throw std::invalid_argument("span '" + std::string(choice) + "': " + e);
  }
  if (const std::string problem = fits(name, span); !problem.empty()) {
    p.name = "whole_run";
    p.warning = "span " + std::string(choice) + ": " + problem + ": scored over the whole run";
  }
  return p;
}

/// Scores `estimates` with protocol `p` (its span, or the whole run).
inline ProtocolRmse score_2d(std::span<const TimedPoint2> estimates, std::span<const io::HanyangReferencePose> reference,
                             const ScoringProtocol& p, std::vector<double>* errors = nullptr) {
  return p.span ? hanyang_rmse_2d(estimates, reference, *p.span, errors) : plain_rmse_2d(estimates, reference, errors);
}

/// A trajectory CSV: ours (time_ns, x, y, z; `ctxfuse run uwb --out`) or the authors' LS.csv /
/// ESKF.csv (timestamp [ns], x, y, z); the time column is found by either name, x and y by
/// name; stamps must not decrease.
inline std::vector<TimedPoint2> read_hanyang_estimates(const std::filesystem::path& file_path) {
  io::TextFile file(file_path);
  const io::Header header = io::read_header(file, io::Separator::comma);
  std::array<std::size_t, 3> c{};
  auto column = [&](std::initializer_list<std::string_view> names) {
    for (std::size_t i = 0; i < header.size(); ++i)
      for (std::string_view n : names)
        if (io::detail::bare_column_name(io::trim(header.name(i))) == n) return i;
    file.fail(io::cat("header has no column ", io::quote(*names.begin()),
                      names.size() > 1 ? io::cat(" or ", io::quote(*(names.begin() + 1))) : std::string()));
  };
  c[0] = column({"timestamp", "time_ns"});
  c[1] = column({"x"});
  c[2] = column({"y"});
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

}  // namespace ctxfuse::studies

// Reader of an IMU csv logged by RTKLIB's str2str with its binary time-tag file (.tag,
// io/time_tag.hpp), and the mapping of the IMU's own millisecond ticks to GPS time.
//
// - csv: 7 fields a line, accel x,y,z [g], gyro x,y,z [deg/s], tick [ms of the IMU's clock],
//   no header. A logger started or stopped mid-line leaves a partial first or last line. The
//   first line is skipped when it is not a whole record; the last line also when it has no
//   newline, since a cut tick ("81049" for "810496") still parses. Both are counted. Anywhere
//   else a bad line is an error: it would mean the file is damaged, not cut.
// - Time (ImuClock): the csv's first kept record is the tag's start time. Ticks are scaled so
//   that the csv's first-to-last tick span equals the last tag record's PC tick, which corrects
//   the IMU clock's rate against the PC's, when that scale is one two clocks can have (see
//   ImuClock). Otherwise one of the files is cut short (or they do not belong together): the
//   ticks are then taken at their nominal 1 ms from the start time, or refused on request, and
//   ImuTimeMapping says which and why.
// - The tag's byte offsets are not used for time: they count the logger's own line endings,
//   which a copied csv need not keep (the drive's csv has LF, its tag counts CRLF), so they
//   place a byte of the csv only to within one byte a line, about 2 % of the file. They are
//   used to say which file is cut.
// - Writing: write_imu_csv_and_tag writes both files in the layout read here (imu_tag_write.hpp).
#pragma once

#include <ctxfuse/messages/sensors.hpp>
#include <ctxfuse/io/text.hpp>
#include <ctxfuse/io/time_tag.hpp>

#include <Eigen/Core>

#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <numbers>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace ctxfuse::io {

struct ImuCsvRecord {
  Eigen::Vector3d accel_g = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_dps = Eigen::Vector3d::Zero();
  std::int64_t tick_ms = 0;
  std::size_t line = 0;
};

struct ImuCsvLog {
  std::string file;
  std::vector<ImuCsvRecord> records;
  bool skipped_first_line = false;
  bool skipped_last_line = false;
  std::uint64_t bytes = 0;  // size of the file
  std::size_t lines = 0;    // lines in the file, blank ones and a last one without newline included
  std::size_t skipped_lines() const { return std::size_t{skipped_first_line} + std::size_t{skipped_last_line}; }
};

namespace detail {

inline ImuCsvRecord parse_imu_fields(const Fields& f) {
  f.expect_count(7);
  // Bounds far beyond any MEMS range: they catch a corrupt line, not a hard manoeuvre.
  ImuCsvRecord r;
  for (int k = 0; k < 3; ++k) r.accel_g[k] = f.real_in(static_cast<std::size_t>(k), -100.0, 100.0);
  for (int k = 0; k < 3; ++k) r.gyro_dps[k] = f.real_in(static_cast<std::size_t>(3 + k), -1e4, 1e4);
  r.tick_ms = f.integer<std::int64_t>(6, 0, std::int64_t{1} << 52);
  r.line = f.line();
  return r;
}

}  // namespace detail

inline ImuCsvLog read_imu_csv(const std::filesystem::path& path) {
  TextFile file(path);
  ImuCsvLog log;
  log.file = file.name();
  Fields f(file.name());
  // A line is parsed once the next is read, so that the last one is known to be last.
  std::string pending;
  std::size_t pending_line = 0;
  bool pending_complete = true, have_pending = false;
  auto take = [&](bool is_last) {
    const bool is_first = log.records.empty() && !log.skipped_first_line;
    f.split(pending, pending_line, Separator::comma);
    ImuCsvRecord r;
    if (is_last && !pending_complete) {
      log.skipped_last_line = true;
      return;
    }
    if (is_first || is_last) {
      try {
        r = detail::parse_imu_fields(f);
      } catch (const ParseError&) {
        (is_first ? log.skipped_first_line : log.skipped_last_line) = true;
        return;
      }
    } else {
      r = detail::parse_imu_fields(f);
    }
    if (!log.records.empty() && r.tick_ms <= log.records.back().tick_ms)
      f.fail(6, cat("tick ", r.tick_ms, " is not after the previous record's ", log.records.back().tick_ms, " (line ",
                    log.records.back().line, ")"));
    log.records.push_back(r);
  };
  std::string_view line;
  while (file.next(line)) {
    if (trim(line).empty()) continue;
    if (have_pending) take(false);
    pending.assign(line);
    pending_line = file.line_number();
    pending_complete = file.ended_by_newline();
    have_pending = true;
  }
  if (have_pending) take(true);
  log.lines = file.line_number();
  std::error_code ec;
  log.bytes = std::filesystem::file_size(path, ec);
  if (ec) log.bytes = 0;
  return log;
}

/// Frequency error allowed to each of the two clocks compared (the IMU's oscillator and the
/// logging PC's millisecond tick). Quartz crystals are specified at +-10 to +-50 ppm at 25 C,
/// with about as much again over an industrial temperature range and a few ppm a year of
/// ageing; typical parts agree within a few tens of ppm. 100 ppm bounds a cheap part over
/// temperature, so two clocks differ by at most 200 ppm.
inline constexpr double kClockTolerancePpm = 100.0;

/// How the ticks of one csv were mapped to GPS time, for the caller to print or log.
struct ImuTimeMapping {
  enum class Method { scaled, nominal };
  Method method = Method::scaled;
  double seconds_per_tick = 1e-3;  // used: the fit (scaled) or 1 ms (nominal)
  double scale_ppm = 0.0;          // the fit's rate error, (fit / 1 ms - 1) * 1e6, used or not
  double tolerance_ppm = 0.0;      // the largest |scale_ppm| taken as a clock's
  double csv_span_s = 0.0;         // first to last kept tick, at 1 ms a tick
  double tag_span_s = 0.0;         // the last tag record's tick
  std::uint64_t csv_bytes = 0;
  std::size_t csv_lines = 0;
  std::uint32_t tag_last_offset = 0;  // bytes of logged data the tag accounts for
  std::string why;                    // one sentence: the figures and the conclusion
};

inline const char* to_string(ImuTimeMapping::Method m) { return m == ImuTimeMapping::Method::scaled ? "scaled" : "nominal"; }

/// What ImuClock does with a tick scale no pair of clocks has.
enum class ImplausibleTickScale { use_nominal, refuse };

namespace detail {
/// v with `decimals` digits after the point, for messages.
inline std::string fixed(double v, int decimals) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, decimals);
  return std::string(buf, r.ptr);
}

/// What the byte counts add. The logger may have written CRLF where the copy has LF or the
/// reverse, so the logged size is known only to within the csv's bytes +- its lines.
inline std::string byte_evidence(const ImuTimeMapping& m) {
  if (m.csv_bytes == 0) return "the csv's size is unknown";
  const auto lo = m.csv_bytes > m.csv_lines ? m.csv_bytes - m.csv_lines : 0, hi = m.csv_bytes + m.csv_lines;
  const std::string counts = cat("the tag accounts for ", m.tag_last_offset, " bytes of logged data, the csv has ",
                                 m.csv_bytes, " bytes in ", m.csv_lines, " lines (", lo, " to ", hi,
                                 " with either line ending)");
  if (m.tag_last_offset > hi) return counts + ": the csv is cut short";
  if (m.tag_last_offset < lo) return counts + ": the tag is cut short";
  return counts + ": the sizes agree to within the line endings";
}
}  // namespace detail

/// IMU tick -> GPST seconds since 1970 (see the file comment).
///
/// The scale fit compares two spans: the csv's ticks, first to last kept record, and the tag's
/// last PC tick. Beside the two clocks' rate difference (at most 2 * kClockTolerancePpm), the
/// fit absorbs the logger's latency at both ends: the first record reached the PC by the first
/// tag record's tick, not at the start time, and the last record up to one tag step before the
/// last tag tick; a partial line skipped at either end shifts the span by one IMU step more.
/// The fit is used when |tag span - csv span| is within the sum of those bounds. The drive in
/// shared/data fits at +257 ppm, almost all of it its 0.131 s start latency over 549 s, against
/// a bound of about 500 ppm; its csv cut at 1 MB would need a scale of 2.5.
class ImuClock {
 public:
  ImuClock(const ImuCsvLog& log, const TimeTag& tag, ImplausibleTickScale policy = ImplausibleTickScale::use_nominal) {
    if (log.records.size() < 2) throw ParseError(log.file, 0, 0, "", "fewer than 2 records: no tick span to scale");
    if (tag.records.empty()) throw ParseError(tag.file, 0, 0, "", "no tick records");
    const double last_tag_s = tag.records.back().tick_ms / 1000.0;
    if (!(last_tag_s > 0.0)) throw ParseError(tag.file, 0, 0, "", "last tick record is 0 ms: no span to scale to");
    start_ = tag.start_time();
    first_tick_ = log.records.front().tick_ms;
    const auto ticks = static_cast<double>(log.records.back().tick_ms - first_tick_);
    const double fit = last_tag_s / ticks;

    auto& m = mapping_;
    m.csv_span_s = ticks / 1000.0;
    m.tag_span_s = last_tag_s;
    m.scale_ppm = (fit / 1e-3 - 1.0) * 1e6;
    m.csv_bytes = log.bytes;
    m.csv_lines = log.lines;
    m.tag_last_offset = tag.records.back().byte_offset;
    const std::size_t n = tag.records.size();
    const double first_latency_s = tag.records.front().tick_ms / 1000.0;
    const double last_step_s = n > 1 ? (tag.records[n - 1].tick_ms - tag.records[n - 2].tick_ms) / 1000.0 : 0.0;
    const double imu_step_s = m.csv_span_s / static_cast<double>(log.records.size() - 1);
    const double latency_s = first_latency_s + last_step_s + 2.0 * imu_step_s;
    const double tolerance_s = 2.0 * kClockTolerancePpm * 1e-6 * m.csv_span_s + latency_s;
    m.tolerance_ppm = tolerance_s / m.csv_span_s * 1e6;
    const bool plausible = std::abs(last_tag_s - m.csv_span_s) <= tolerance_s;

    std::string figures = cat("csv ticks span ", detail::fixed(m.csv_span_s, 3), " s, the tag ",
                              detail::fixed(last_tag_s, 3), " s: scale ", detail::fixed(m.scale_ppm, 1),
                              " ppm against a bound of ", detail::fixed(m.tolerance_ppm, 1),
                              " ppm (two clocks at ", kClockTolerancePpm, " ppm, latency ", detail::fixed(latency_s, 3),
                              " s)");
    if (tag.partial_record_bytes)
      figures += cat("; the tag's last record was cut (", tag.partial_record_bytes, " of 8 bytes, dropped)");
    if (plausible) {
      m.method = ImuTimeMapping::Method::scaled;
      m.seconds_per_tick = fit;
      m.why = figures + ": ticks scaled to the tag";
    } else {
      m.method = ImuTimeMapping::Method::nominal;
      m.seconds_per_tick = 1e-3;
      const double gap_s = last_tag_s - m.csv_span_s;
      m.why = cat(figures, ", a scale no clock has: ",
                  gap_s > 0.0 ? cat("the csv ends ", detail::fixed(gap_s, 3), " s before the tag")
                              : cat("the tag ends ", detail::fixed(-gap_s, 3), " s before the csv"),
                  "; ", detail::byte_evidence(m), ". ");
      if (policy == ImplausibleTickScale::refuse)
        throw ParseError(log.file, 0, 0, "", m.why + "Refused (the csv and its tag " + tag.file + " do not agree)");
      m.why += "Ticks taken at the nominal 1 ms from the tag's start time";
    }
    seconds_per_tick_ = m.seconds_per_tick;
  }
  double operator()(std::int64_t tick_ms) const {
    return start_ + static_cast<double>(tick_ms - first_tick_) * seconds_per_tick_;
  }
  /// Seconds of GPS time per IMU millisecond tick (1e-3 for clocks that agree, and when the
  /// nominal mapping is used).
  double seconds_per_tick() const { return seconds_per_tick_; }
  const ImuTimeMapping& mapping() const { return mapping_; }

 private:
  double start_ = 0.0;
  std::int64_t first_tick_ = 0;
  double seconds_per_tick_ = 0.0;
  ImuTimeMapping mapping_;
};

struct ImuConversion {
  /// Added to every time: the logging delay of the set-up (the data README gives -0.125 s for
  /// its drive); zero by default so that no recording's figure is assumed for another.
  double delay_s = 0.0;
  double g_mps2 = 9.80665;  // standard gravity: the unit the csv's accelerations are in
  ImplausibleTickScale implausible_scale = ImplausibleTickScale::use_nominal;
};

/// Samples in SI units in the IMU's axes (rad/s, m/s^2), rates not increments. `mapping`,
/// when given, receives how the ticks were mapped to time.
inline std::vector<messages::ImuSample> to_imu_samples(const ImuCsvLog& log, const TimeTag& tag, const ImuConversion& opt = {},
                                             ImuTimeMapping* mapping = nullptr) {
  const ImuClock clock(log, tag, opt.implausible_scale);
  if (mapping) *mapping = clock.mapping();
  constexpr double rad_per_deg = std::numbers::pi / 180.0;
  std::vector<messages::ImuSample> out;
  out.reserve(log.records.size());
  for (const auto& r : log.records) {
    messages::ImuSample s;
    s.t = clock(r.tick_ms) + opt.delay_s;
    s.gyro = r.gyro_dps * rad_per_deg;
    s.accel = r.accel_g * opt.g_mps2;
    out.push_back(s);
  }
  return out;
}

}  // namespace ctxfuse::io

#include <ctxfuse/io/imu_tag_write.hpp>

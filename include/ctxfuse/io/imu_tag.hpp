// Reader of an IMU csv logged by RTKLIB's str2str with its binary time-tag file (.tag), and
// the mapping of the IMU's own millisecond ticks to GPS time.
//
// - csv: 7 fields a line, accel x,y,z [g], gyro x,y,z [deg/s], tick [ms of the IMU's clock],
//   no header. A logger started or stopped mid-line leaves a partial first or last line. The
//   first line is skipped when it is not a whole record; the last line also when it has no
//   newline, since a cut tick ("81049" for "810496") still parses. Both are counted. Anywhere
//   else a bad line is an error: it would mean the file is damaged, not cut.
// - tag: a 60-byte header starting "TIMETAG RTKLIB", a uint32 (the data README calls it a
//   time-zone flag; the mapping does not use it), the start time as uint32 seconds plus a
//   double fraction, both GPS time on RTKLIB's 1970-based scale, then (uint32 PC tick [ms]
//   since the start, uint32 byte offset in the csv) records; all little-endian.
// - Time: the csv's first kept record is the tag's start time, and IMU ticks are scaled so
//   that the csv's first-to-last tick span equals the last tag record's PC tick, which corrects
//   the IMU clock's rate against the PC's. The byte offsets are not used: they count the
//   logger's own line endings, which a copied csv need not keep.
#pragma once

#include <ctxfuse/io/messages.hpp>
#include <ctxfuse/io/text.hpp>

#include <Eigen/Core>

#include <bit>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <numbers>
#include <string>
#include <string_view>
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
  return log;
}

struct TimeTagRecord {
  std::uint32_t tick_ms = 0;      // PC clock since the start
  std::uint32_t byte_offset = 0;  // in the csv as the logger wrote it
};

struct TimeTag {
  std::string file;
  std::uint32_t header_word = 0;  // the uint32 after the 60-byte header (unused)
  std::uint32_t start_s = 0;      // GPST seconds since 1970, no leap seconds
  double start_fraction_s = 0.0;
  std::vector<TimeTagRecord> records;
  double start_time() const { return static_cast<double>(start_s) + start_fraction_s; }
};

inline constexpr std::string_view kTimeTagMagic = "TIMETAG RTKLIB";
inline constexpr std::size_t kTimeTagHeaderBytes = 60;
inline constexpr std::size_t kTimeTagPreambleBytes = kTimeTagHeaderBytes + 4 + 4 + 8;

namespace detail {
inline std::uint64_t little_endian(const unsigned char* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
}  // namespace detail

inline TimeTag read_time_tag(const std::filesystem::path& path) {
  TimeTag tag;
  tag.file = path.string();
  auto fail = [&](std::string reason) { throw ParseError(tag.file, 0, 0, "", std::move(reason)); };
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("cannot open file");
  const std::vector<unsigned char> b{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (b.size() < kTimeTagPreambleBytes)
    fail(cat("file too short: ", b.size(), " bytes, a time-tag file starts with ", kTimeTagPreambleBytes,
             " (60-byte header, flag, start time)"));
  if (std::string_view(reinterpret_cast<const char*>(b.data()), kTimeTagMagic.size()) != kTimeTagMagic)
    fail("header does not start with \"TIMETAG RTKLIB\": not an RTKLIB time-tag file");
  const unsigned char* p = b.data() + kTimeTagHeaderBytes;
  tag.header_word = static_cast<std::uint32_t>(detail::little_endian(p, 4));
  tag.start_s = static_cast<std::uint32_t>(detail::little_endian(p + 4, 4));
  tag.start_fraction_s = std::bit_cast<double>(detail::little_endian(p + 8, 8));
  if (!(tag.start_fraction_s >= 0.0 && tag.start_fraction_s < 1.0))
    fail(cat("start-time fraction ", tag.start_fraction_s, " outside [0, 1) s"));
  const std::size_t body = b.size() - kTimeTagPreambleBytes;
  if (body % 8 != 0)
    fail(cat("truncated: the last record has ", body % 8, " of its 8 bytes (file size ", b.size(), ")"));
  if (body == 0) fail("no tick records after the header");
  tag.records.reserve(body / 8);
  for (std::size_t off = kTimeTagPreambleBytes; off < b.size(); off += 8) {
    const TimeTagRecord r{static_cast<std::uint32_t>(detail::little_endian(b.data() + off, 4)),
                          static_cast<std::uint32_t>(detail::little_endian(b.data() + off + 4, 4))};
    if (!tag.records.empty() && (r.tick_ms < tag.records.back().tick_ms || r.byte_offset < tag.records.back().byte_offset))
      fail(cat("record at byte ", off, " goes backwards (tick ", r.tick_ms, ", offset ", r.byte_offset, ")"));
    tag.records.push_back(r);
  }
  return tag;
}

/// IMU tick -> GPST seconds since 1970, as the data README specifies (see the file comment).
class ImuClock {
 public:
  ImuClock(const ImuCsvLog& log, const TimeTag& tag) {
    if (log.records.size() < 2) throw ParseError(log.file, 0, 0, "", "fewer than 2 records: no tick span to scale");
    const double last_tag_s = tag.records.back().tick_ms / 1000.0;
    if (!(last_tag_s > 0.0)) throw ParseError(tag.file, 0, 0, "", "last tick record is 0 ms: no span to scale to");
    start_ = tag.start_time();
    first_tick_ = log.records.front().tick_ms;
    seconds_per_tick_ = last_tag_s / static_cast<double>(log.records.back().tick_ms - first_tick_);
  }
  double operator()(std::int64_t tick_ms) const {
    return start_ + static_cast<double>(tick_ms - first_tick_) * seconds_per_tick_;
  }
  /// Seconds of GPS time per IMU millisecond tick (1e-3 for clocks that agree).
  double seconds_per_tick() const { return seconds_per_tick_; }

 private:
  double start_ = 0.0;
  std::int64_t first_tick_ = 0;
  double seconds_per_tick_ = 0.0;
};

struct ImuConversion {
  /// Added to every time: the logging delay of the set-up (the data README gives -0.125 s for
  /// its drive); zero by default so that no recording's figure is assumed for another.
  double delay_s = 0.0;
  double g_mps2 = 9.80665;  // standard gravity: the unit the csv's accelerations are in
};

/// Samples in SI units in the IMU's axes (rad/s, m/s^2), rates not increments.
inline std::vector<ImuSample> to_imu_samples(const ImuCsvLog& log, const TimeTag& tag, const ImuConversion& opt = {}) {
  const ImuClock clock(log, tag);
  constexpr double rad_per_deg = std::numbers::pi / 180.0;
  std::vector<ImuSample> out;
  out.reserve(log.records.size());
  for (const auto& r : log.records) {
    ImuSample s;
    s.t = clock(r.tick_ms) + opt.delay_s;
    s.gyro = r.gyro_dps * rad_per_deg;
    s.accel = r.accel_g * opt.g_mps2;
    out.push_back(s);
  }
  return out;
}

}  // namespace ctxfuse::io

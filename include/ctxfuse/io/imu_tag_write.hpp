// Writer of an IMU csv with its RTKLIB time-tag file, in the layout io/imu_tag.hpp reads, so
// that a simulated recording reads as a logged one.
//
// - The csv: accel x,y,z [g], gyro x,y,z [deg/s], tick [integer ms of the IMU's own clock],
//   one record a line, no header. Values are written as the shortest text that reads back to
//   the same double, or with a fixed number of decimals (a logger's 3, say) when asked.
// - The tag: the start time, then one record per `lines_per_tag_record` lines: the PC tick
//   [ms since the start, rounded] at which the group's last line reached the logger, and the
//   csv's size in bytes after that line, counting the line ending written.
// - The caller gives the IMU ticks and the PC times separately, so that a simulated IMU clock
//   may run fast or slow and its stamps may jitter. The reader takes the first record to be at
//   the start time and scales ticks to the last tag tick: a recording whose first record
//   reaches the PC at the start time and whose last record is the last tag record reads back
//   with the simulated rate error removed.
// Throws std::invalid_argument, before writing anything, for what the reader would refuse or
// misread; std::runtime_error when a file cannot be written.
#pragma once

#include <ctxfuse/io/imu_tag.hpp>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace ctxfuse::io {

struct ImuCsvWriteOptions {
  int decimals = -1;                    // for accel and gyro; -1: shortest round-trip text
  std::string_view line_ending = "\n";  // "\r\n" for a Windows logger; the tag's offsets count it
  std::size_t lines_per_tag_record = 1;
  std::string_view tag_magic = "TIMETAG RTKLIB ctxfuse";
};

namespace detail {
inline void append_number(std::string& out, double v, int decimals) {
  char buf[64];
  const auto r = decimals < 0 ? std::to_chars(buf, buf + sizeof buf, v)
                              : std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, decimals);
  out.append(buf, r.ptr);
}
inline void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream os(path, std::ios::binary | std::ios::trunc);
  os.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!os.flush()) throw std::runtime_error("cannot write " + path.string());
}
}  // namespace detail

/// `records`: values and IMU ticks (the `line` member is ignored); `received_s[i]`: seconds
/// after `start_time` (GPST, seconds since 1970) at which record i reached the logger. Writes
/// `csv_path` and `csv_path` + ".tag".
inline void write_imu_csv_and_tag(const std::filesystem::path& csv_path, std::span<const ImuCsvRecord> records,
                                  std::span<const double> received_s, double start_time,
                                  const ImuCsvWriteOptions& opt = {}) {
  auto bad = [](std::string what) { throw std::invalid_argument("write_imu_csv_and_tag: " + what); };
  if (records.size() < 2) bad("fewer than 2 records: the reader needs a tick span");
  if (received_s.size() != records.size()) bad(cat(received_s.size(), " receive times for ", records.size(), " records"));
  if (opt.lines_per_tag_record == 0) bad("lines_per_tag_record is 0");
  if (opt.line_ending != "\n" && opt.line_ending != "\r\n") bad("line ending is neither LF nor CRLF");
  if (opt.decimals > 17) bad(cat(opt.decimals, " decimals"));
  for (std::size_t i = 0; i < records.size(); ++i) {
    const auto& r = records[i];
    if (!r.accel_g.allFinite() || (r.accel_g.array().abs() > 100.0).any()) bad(cat("record ", i, ": accel not finite or beyond 100 g"));
    if (!r.gyro_dps.allFinite() || (r.gyro_dps.array().abs() > 1e4).any())
      bad(cat("record ", i, ": gyro not finite or beyond 1e4 deg/s"));
    if (r.tick_ms < 0 || r.tick_ms > (std::int64_t{1} << 52)) bad(cat("record ", i, ": tick ", r.tick_ms, " outside [0, 2^52]"));
    if (i > 0 && r.tick_ms <= records[i - 1].tick_ms) bad(cat("record ", i, ": tick ", r.tick_ms, " does not increase"));
    if (!(received_s[i] >= 0.0 && received_s[i] * 1000.0 < 4294967295.0))
      bad(cat("record ", i, ": receive time ", received_s[i], " s outside the tag's uint32 ms"));
    if (i > 0 && received_s[i] < received_s[i - 1]) bad(cat("record ", i, ": receive time goes backwards"));
  }
  std::string csv;
  csv.reserve(records.size() * 64);
  std::vector<TimeTagRecord> tags;
  tags.reserve(records.size() / opt.lines_per_tag_record + 1);
  for (std::size_t i = 0; i < records.size(); ++i) {
    const auto& r = records[i];
    for (const Eigen::Vector3d* v : {&r.accel_g, &r.gyro_dps})
      for (int k = 0; k < 3; ++k) {
        detail::append_number(csv, (*v)[k], opt.decimals);
        csv.push_back(',');
      }
    csv.append(std::to_string(r.tick_ms)).append(opt.line_ending);
    if ((i + 1) % opt.lines_per_tag_record == 0 || i + 1 == records.size()) {
      if (csv.size() > 0xffffffffu) bad("csv larger than the tag's uint32 byte offsets");
      tags.push_back({static_cast<std::uint32_t>(std::llround(received_s[i] * 1000.0)), static_cast<std::uint32_t>(csv.size())});
    }
  }
  const std::string tag = time_tag_bytes(start_time, tags, opt.tag_magic);
  detail::write_bytes(csv_path, csv);
  detail::write_bytes(csv_path.string() + ".tag", tag);
}

/// The same from SI samples (rates, not increments: gyro [rad/s], accel [m/s^2]) in the IMU's
/// axes: sample i reached the logger at samples[i].t (GPST), its IMU tick is ticks_ms[i].
/// `g_mps2` is the unit the accelerations are written in, as ImuConversion reads them.
inline void write_imu_csv_and_tag(const std::filesystem::path& csv_path, std::span<const messages::ImuSample> samples,
                                  std::span<const std::int64_t> ticks_ms, double start_time,
                                  const ImuCsvWriteOptions& opt = {}, double g_mps2 = 9.80665) {
  if (ticks_ms.size() != samples.size())
    throw std::invalid_argument(cat("write_imu_csv_and_tag: ", ticks_ms.size(), " ticks for ", samples.size(), " samples"));
  std::vector<ImuCsvRecord> records(samples.size());
  std::vector<double> received(samples.size());
  constexpr double deg_per_rad = 180.0 / std::numbers::pi;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (samples[i].increments) throw std::invalid_argument("write_imu_csv_and_tag: increments, not rates");
    records[i].accel_g = samples[i].accel / g_mps2;
    records[i].gyro_dps = samples[i].gyro * deg_per_rad;
    records[i].tick_ms = ticks_ms[i];
    received[i] = samples[i].t - start_time;
  }
  write_imu_csv_and_tag(csv_path, records, received, start_time, opt);
}

}  // namespace ctxfuse::io

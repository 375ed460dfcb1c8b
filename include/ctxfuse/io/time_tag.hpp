// RTKLIB's binary time-tag file (.tag), written by str2str beside a logged stream: when each
// piece of the stream reached the logging PC.
//
// - Layout, all little-endian: a 60-byte header starting "TIMETAG RTKLIB" (NUL-padded), a
//   uint32 (the data README calls it a time-zone flag; nothing here uses it), the start time as
//   uint32 seconds plus a double fraction, both GPS time on RTKLIB's 1970-based scale, then
//   records of (uint32 PC tick [ms] since the start, uint32 byte offset in the logged file).
// - A file cut inside its 76-byte preamble is refused (no start time). A file cut inside a
//   record is read to its last whole record; `partial_record_bytes` says how many bytes of the
//   cut record were dropped, so that a caller can report it.
// - Ticks and offsets must not decrease; a record that goes backwards is an error.
#pragma once

#include <ctxfuse/io/text.hpp>

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace ctxfuse::io {

struct TimeTagRecord {
  std::uint32_t tick_ms = 0;      // PC clock since the start
  std::uint32_t byte_offset = 0;  // in the logged file, as the logger wrote it
};

struct TimeTag {
  std::string file;
  std::uint32_t header_word = 0;  // the uint32 after the 60-byte header (unused)
  std::uint32_t start_s = 0;      // GPST seconds since 1970, no leap seconds
  double start_fraction_s = 0.0;
  std::vector<TimeTagRecord> records;
  std::size_t partial_record_bytes = 0;  // bytes of a cut last record, dropped (0-7)
  double start_time() const { return static_cast<double>(start_s) + start_fraction_s; }
};

inline constexpr std::string_view kTimeTagMagic = "TIMETAG RTKLIB";
inline constexpr std::size_t kTimeTagHeaderBytes = 60;
inline constexpr std::size_t kTimeTagPreambleBytes = kTimeTagHeaderBytes + 4 + 4 + 8;
inline constexpr std::size_t kTimeTagRecordBytes = 8;

namespace detail {
inline std::uint64_t little_endian(const unsigned char* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
inline void put_little_endian(std::string& out, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xffu));
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
  tag.partial_record_bytes = body % kTimeTagRecordBytes;
  if (body < kTimeTagRecordBytes)
    fail(tag.partial_record_bytes ? cat("no whole tick record after the header (", tag.partial_record_bytes, " of 8 bytes)")
                                  : std::string("no tick records after the header"));
  const std::size_t end = b.size() - tag.partial_record_bytes;
  tag.records.reserve(body / kTimeTagRecordBytes);
  for (std::size_t off = kTimeTagPreambleBytes; off < end; off += kTimeTagRecordBytes) {
    const TimeTagRecord r{static_cast<std::uint32_t>(detail::little_endian(b.data() + off, 4)),
                          static_cast<std::uint32_t>(detail::little_endian(b.data() + off + 4, 4))};
    if (!tag.records.empty() && (r.tick_ms < tag.records.back().tick_ms || r.byte_offset < tag.records.back().byte_offset))
      fail(cat("record at byte ", off, " goes backwards (tick ", r.tick_ms, ", offset ", r.byte_offset, ")"));
    tag.records.push_back(r);
  }
  return tag;
}

/// The bytes of a time-tag file: `magic` (which must start with "TIMETAG RTKLIB", at most 60
/// bytes) NUL-padded to 60, the header word, the start time split into whole seconds and
/// fraction, then the records. Throws std::invalid_argument for what read_time_tag refuses.
inline std::string time_tag_bytes(double start_time, std::span<const TimeTagRecord> records,
                                  std::string_view magic = "TIMETAG RTKLIB ctxfuse", std::uint32_t header_word = 0) {
  if (magic.substr(0, kTimeTagMagic.size()) != kTimeTagMagic || magic.size() > kTimeTagHeaderBytes)
    throw std::invalid_argument("time_tag_bytes: the header must start with \"TIMETAG RTKLIB\" and fit in 60 bytes");
  if (!(std::isfinite(start_time) && start_time >= 0.0 && start_time < 4294967296.0))
    throw std::invalid_argument(cat("time_tag_bytes: start time ", start_time, " s is not a uint32 second count"));
  if (records.empty()) throw std::invalid_argument("time_tag_bytes: no records");
  for (std::size_t i = 1; i < records.size(); ++i)
    if (records[i].tick_ms < records[i - 1].tick_ms || records[i].byte_offset < records[i - 1].byte_offset)
      throw std::invalid_argument(cat("time_tag_bytes: record ", i, " goes backwards"));
  const double whole = std::floor(start_time);
  std::string out(magic);
  out.resize(kTimeTagHeaderBytes, '\0');
  detail::put_little_endian(out, header_word, 4);
  detail::put_little_endian(out, static_cast<std::uint32_t>(whole), 4);
  detail::put_little_endian(out, std::bit_cast<std::uint64_t>(start_time - whole), 8);
  for (const auto& r : records) {
    detail::put_little_endian(out, r.tick_ms, 4);
    detail::put_little_endian(out, r.byte_offset, 4);
  }
  return out;
}

}  // namespace ctxfuse::io

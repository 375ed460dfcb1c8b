// Reader of RTKLIB solution files (.pos) in the lat/lon/height format with GPST calendar time
// ("yyyy/mm/dd hh:mm:ss.sss"), and their conversion to messages::GnssFix.
//
// - The column layout comes from the last header line, "%  GPST  latitude(deg) ...": RTKLIB
//   drops the standard-deviation and velocity columns depending on its output options, and
//   other tools write the same format with their own selection, so no position is assumed.
//   Columns this reader does not know are ignored; the position, Q and ns are required.
// - Times are GPS seconds since 1970-01-01 without leap seconds (RTKLIB's gtime_t scale), so
//   they compare directly with the IMU time tags of imu_tag.hpp. A UTC or JST file is refused
//   rather than converted: shifting it by the leap seconds would need a table this reader
//   would have to keep up to date.
// - RTKLIB writes each covariance term c as sign(c) * sqrt(|c|) (sdn, sdne, ...); records keep
//   the file's values and to_gnss_fix squares them back with their signs.
// - Epochs must strictly increase; anything malformed throws ParseError (file:line:column).
// - A last line without a newline is not trusted: a copy cut inside a number still parses
//   ("1601.47" for "1601.4740000"), so it is skipped and counted (skipped_partial_last_line).
// - write_rtklib_pos writes the same format with every column: RTKLIB's widths and decimals
//   (time to the ms, lat/lon 9 decimals [deg], height 4 [m], sd 4 [m], age 2 [s], ratio 1,
//   velocities 5 [m/s] and their sd 5); a file the reader takes back unchanged to those digits.
#pragma once

#include <ctxfuse/messages/sensors.hpp>
#include <ctxfuse/io/text.hpp>

#include <Eigen/Core>

#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ctxfuse::io {

/// One epoch as written. Columns absent from the file are NaN.
struct RtklibPosRecord {
  double t = 0.0;  // GPST, seconds since 1970-01-01 without leap seconds
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double height_m = 0.0;  // as the file gives it (ellipsoidal or above MSL: the writer's choice)
  int q = 0;              // 1 fix, 2 float, 3 SBAS, 4 DGPS, 5 single, 6 PPP, 7 dead reckoning
  int ns = 0;
  double sdn_m = messages::kUnknown, sde_m = messages::kUnknown, sdu_m = messages::kUnknown;
  double sdne_m = messages::kUnknown, sdeu_m = messages::kUnknown, sdun_m = messages::kUnknown;  // signed square roots
  double age_s = messages::kUnknown, ratio = messages::kUnknown;
  double vn_mps = messages::kUnknown, ve_mps = messages::kUnknown, vu_mps = messages::kUnknown;
  double sdvn_mps = messages::kUnknown, sdve_mps = messages::kUnknown, sdvu_mps = messages::kUnknown;
  double sdvne_mps = messages::kUnknown, sdveu_mps = messages::kUnknown, sdvun_mps = messages::kUnknown;
  std::size_t line = 0;

  bool has_position_sd() const { return std::isfinite(sdn_m) && std::isfinite(sde_m) && std::isfinite(sdu_m); }
  bool has_velocity() const { return std::isfinite(vn_mps) && std::isfinite(ve_mps) && std::isfinite(vu_mps); }
};

struct RtklibPosFile {
  std::vector<RtklibPosRecord> records;
  std::vector<std::string> columns;  // the header's names after the two GPST fields
  bool skipped_partial_last_line = false;  // a data line without newline at the end of the file
};

namespace detail {

struct PosColumn {
  std::string_view name;
  double RtklibPosRecord::*member;
  double lo, hi;
};

// Bounds wide enough for any real receiver; they catch corrupt lines, not poor solutions.
inline constexpr PosColumn kPosColumns[] = {
    {"latitude(deg)", &RtklibPosRecord::latitude_deg, -90.0, 90.0},
    {"longitude(deg)", &RtklibPosRecord::longitude_deg, -180.0, 180.0},
    {"height(m)", &RtklibPosRecord::height_m, -1e4, 1e5},
    {"sdn(m)", &RtklibPosRecord::sdn_m, 0.0, 1e6},
    {"sde(m)", &RtklibPosRecord::sde_m, 0.0, 1e6},
    {"sdu(m)", &RtklibPosRecord::sdu_m, 0.0, 1e6},
    {"sdne(m)", &RtklibPosRecord::sdne_m, -1e6, 1e6},
    {"sdeu(m)", &RtklibPosRecord::sdeu_m, -1e6, 1e6},
    {"sdun(m)", &RtklibPosRecord::sdun_m, -1e6, 1e6},
    {"age(s)", &RtklibPosRecord::age_s, 0.0, 1e6},
    {"ratio", &RtklibPosRecord::ratio, 0.0, 1e6},
    {"vn(m/s)", &RtklibPosRecord::vn_mps, -1e4, 1e4},
    {"ve(m/s)", &RtklibPosRecord::ve_mps, -1e4, 1e4},
    {"vu(m/s)", &RtklibPosRecord::vu_mps, -1e4, 1e4},
    {"sdvn", &RtklibPosRecord::sdvn_mps, 0.0, 1e4},
    {"sdve", &RtklibPosRecord::sdve_mps, 0.0, 1e4},
    {"sdvu", &RtklibPosRecord::sdvu_mps, 0.0, 1e4},
    {"sdvne", &RtklibPosRecord::sdvne_mps, -1e4, 1e4},
    {"sdveu", &RtklibPosRecord::sdveu_mps, -1e4, 1e4},
    {"sdvun", &RtklibPosRecord::sdvun_mps, -1e4, 1e4},
};

/// "yyyy/mm/dd" in field `di` and "hh:mm:ss.sss" in field `ti` -> seconds since 1970 on the
/// time scale the file is written in (no leap seconds are inserted: GPST has none).
inline double parse_calendar_time(const Fields& f, std::size_t di, std::size_t ti) {
  const std::string_view d = f[di], t = f[ti];
  auto part = [&](std::size_t field, std::string_view s, std::size_t& pos, char end, int lo, int hi) {
    const auto stop = end ? s.find(end, pos) : std::string_view::npos;
    const auto text = s.substr(pos, stop == std::string_view::npos ? std::string_view::npos : stop - pos);
    int v = 0;
    if (parse_integer(text, v, lo, hi) != NumberError::none || (end && stop == std::string_view::npos))
      f.fail(field, cat(quote(s), " is not a ", field == di ? "yyyy/mm/dd date" : "hh:mm:ss.sss time"));
    pos = stop == std::string_view::npos ? s.size() : stop + 1;
    return v;
  };
  std::size_t p = 0;
  const int year = part(di, d, p, '/', 1980, 2200), month = part(di, d, p, '/', 1, 12), day = part(di, d, p, 0, 1, 31);
  const std::chrono::year_month_day ymd{std::chrono::year{year}, std::chrono::month{static_cast<unsigned>(month)},
                                        std::chrono::day{static_cast<unsigned>(day)}};
  if (!ymd.ok()) f.fail(di, cat(quote(d), " is not a calendar date"));
  p = 0;
  const int hour = part(ti, t, p, ':', 0, 23), minute = part(ti, t, p, ':', 0, 59);
  double second = 0.0;
  if (parse_real(t.substr(p), second) != NumberError::none || second < 0.0 || second >= 61.0)
    f.fail(ti, cat(quote(t), " is not a hh:mm:ss.sss time"));
  const double days = static_cast<double>(std::chrono::sys_days{ymd}.time_since_epoch().count());
  return days * 86400.0 + hour * 3600.0 + minute * 60.0 + second;
}

}  // namespace detail

inline RtklibPosFile read_rtklib_pos(const std::filesystem::path& path) {
  TextFile file(path);
  RtklibPosFile out;
  Header header;
  bool have_header = false;
  std::vector<std::pair<std::size_t, const detail::PosColumn*>> used;  // data field -> column
  std::size_t c_q = 0, c_ns = 0;
  Fields f(file.name(), &header);
  std::string_view line;
  while (file.next(line)) {
    if (trim(line).empty()) continue;
    if (line.front() == '%') {
      const auto names = split_fields(line.substr(1), Separator::whitespace);
      if (names.empty() || (names[0] != "GPST" && names[0] != "UTC" && names[0] != "JST")) continue;  // comment
      if (names[0] != "GPST")
        file.fail(cat("time system ", names[0], ": only GPST files are read (no leap-second table here)"));
      if (names.size() > 1 && (names[1].substr(0, 4) == "x-ec" || names[1].substr(0, 4) == "e-ba"))
        file.fail(cat("solution format with ", names[1], ": only latitude/longitude/height is read"));
      if (names.size() > 1 && names[1] == "GPST") file.fail("time as GPS week and seconds: only yyyy/mm/dd hh:mm:ss is read");
      std::vector<std::string> cols{"GPST", "GPST"};
      out.columns.assign(names.begin() + 1, names.end());
      cols.insert(cols.end(), out.columns.begin(), out.columns.end());
      header = Header(cols);
      used.clear();
      for (const auto& c : detail::kPosColumns)
        if (const auto i = header.find(c.name)) used.emplace_back(*i, &c);
      for (std::string_view required : {"latitude(deg)", "longitude(deg)", "height(m)", "Q", "ns"})
        (void)require_column(file, header, required);
      c_q = *header.find("Q");
      c_ns = *header.find("ns");
      have_header = true;
      continue;
    }
    if (!have_header) file.fail("data before the '%  GPST ...' column header");
    if (!file.ended_by_newline()) {
      out.skipped_partial_last_line = true;
      break;
    }
    f.split(line, file.line_number(), Separator::whitespace);
    f.expect_count(header.size());
    RtklibPosRecord r;
    r.line = file.line_number();
    r.t = detail::parse_calendar_time(f, 0, 1);
    if (!out.records.empty() && !(r.t > out.records.back().t))
      f.fail(1, cat("epoch is not after the previous one (line ", out.records.back().line, ")"));
    for (const auto& [i, c] : used) r.*(c->member) = f.real_in(i, c->lo, c->hi);
    r.q = f.whole(c_q, 0, 7);
    r.ns = f.whole(c_ns, 0, 255);
    out.records.push_back(r);
  }
  if (!have_header) throw ParseError(file.name(), 0, 0, "", "no '%  GPST ...' column header");
  return out;
}

namespace detail {
inline double signed_square(double s) { return s * std::abs(s); }
}  // namespace detail

/// The epoch as a fix: geodetic (lat, lon [deg], height [m] as written), covariance in east /
/// north / up from the sd columns (NaN when the file has none, so that a filter refuses it
/// rather than trust an invented accuracy), velocity east/north/up when the file has it.
inline messages::GnssFix to_gnss_fix(const RtklibPosRecord& r) {
  using detail::signed_square;
  messages::GnssFix fix;
  fix.t = r.t;
  fix.frame = messages::PositionFrame::geodetic;
  fix.position = {r.latitude_deg, r.longitude_deg, r.height_m};
  const double ne = std::isfinite(r.sdne_m) ? signed_square(r.sdne_m) : 0.0;
  const double eu = std::isfinite(r.sdeu_m) ? signed_square(r.sdeu_m) : 0.0;
  const double un = std::isfinite(r.sdun_m) ? signed_square(r.sdun_m) : 0.0;
  if (r.has_position_sd())
    fix.cov << r.sde_m * r.sde_m, ne, eu,  //
        ne, r.sdn_m * r.sdn_m, un,         //
        eu, un, r.sdu_m * r.sdu_m;
  else
    fix.cov.setConstant(messages::kUnknown);
  if (r.has_velocity()) {
    fix.velocity = Eigen::Vector3d(r.ve_mps, r.vn_mps, r.vu_mps);
    const double vne = std::isfinite(r.sdvne_mps) ? signed_square(r.sdvne_mps) : 0.0;
    const double veu = std::isfinite(r.sdveu_mps) ? signed_square(r.sdveu_mps) : 0.0;
    const double vun = std::isfinite(r.sdvun_mps) ? signed_square(r.sdvun_mps) : 0.0;
    if (std::isfinite(r.sdvn_mps) && std::isfinite(r.sdve_mps) && std::isfinite(r.sdvu_mps))
      fix.velocity_cov << r.sdve_mps * r.sdve_mps, vne, veu,  //
          vne, r.sdvn_mps * r.sdvn_mps, vun,                  //
          veu, vun, r.sdvu_mps * r.sdvu_mps;
    else
      fix.velocity_cov.setConstant(messages::kUnknown);
  }
  fix.quality = r.q >= 1 && r.q <= 6 ? static_cast<messages::FixQuality>(r.q) : messages::FixQuality::unknown;
  fix.satellites_used = r.ns;
  return fix;
}

inline std::vector<messages::GnssFix> to_gnss_fixes(const RtklibPosFile& file) {
  std::vector<messages::GnssFix> out;
  out.reserve(file.records.size());
  for (const auto& r : file.records) out.push_back(to_gnss_fix(r));
  return out;
}

// ---- writer ----

struct RtklibPosWriteOptions {
  bool velocity = true;               // the vn ... sdvun columns (RTKLIB writes them on request)
  std::vector<std::string> comments;  // written as "% text" lines before the column header
};

/// The fix as an epoch of a .pos file: the inverse of to_gnss_fix. The fix must be geodetic
/// (degrees); age and ratio, which a messages::GnssFix does not carry, are 0.
inline RtklibPosRecord to_rtklib_pos_record(const messages::GnssFix& fix) {
  if (fix.frame != messages::PositionFrame::geodetic)
    throw std::invalid_argument("to_rtklib_pos_record: the fix is not geodetic (lat/lon/height)");
  auto root = [](double c) { return std::copysign(std::sqrt(std::abs(c)), c); };
  RtklibPosRecord r;
  r.t = fix.t;
  r.latitude_deg = fix.position.x();
  r.longitude_deg = fix.position.y();
  r.height_m = fix.position.z();
  r.q = static_cast<int>(fix.quality);
  r.ns = fix.satellites_used;
  r.sde_m = std::sqrt(fix.cov(0, 0));
  r.sdn_m = std::sqrt(fix.cov(1, 1));
  r.sdu_m = std::sqrt(fix.cov(2, 2));
  r.sdne_m = root(fix.cov(0, 1));
  r.sdeu_m = root(fix.cov(0, 2));
  r.sdun_m = root(fix.cov(1, 2));
  r.age_s = 0.0;
  r.ratio = 0.0;
  if (fix.velocity) {
    r.ve_mps = fix.velocity->x();
    r.vn_mps = fix.velocity->y();
    r.vu_mps = fix.velocity->z();
    r.sdve_mps = std::sqrt(fix.velocity_cov(0, 0));
    r.sdvn_mps = std::sqrt(fix.velocity_cov(1, 1));
    r.sdvu_mps = std::sqrt(fix.velocity_cov(2, 2));
    r.sdvne_mps = root(fix.velocity_cov(0, 1));
    r.sdveu_mps = root(fix.velocity_cov(0, 2));
    r.sdvun_mps = root(fix.velocity_cov(1, 2));
  }
  return r;
}

namespace detail {
/// "yyyy/mm/dd hh:mm:ss.sss" of seconds since 1970 already rounded to whole milliseconds.
inline std::string calendar_time(long long ms) {
  constexpr long long ms_per_day = 86'400'000;
  const long long days = ms / ms_per_day, in_day = ms % ms_per_day;  // ms >= 0
  const std::chrono::year_month_day ymd{std::chrono::sys_days{std::chrono::days{days}}};
  char buf[40];
  std::snprintf(buf, sizeof buf, "%04d/%02u/%02u %02lld:%02lld:%02lld.%03lld", static_cast<int>(ymd.year()),
                static_cast<unsigned>(ymd.month()), static_cast<unsigned>(ymd.day()), in_day / 3'600'000,
                in_day / 60'000 % 60, in_day / 1000 % 60, in_day % 1000);
  return buf;
}
}  // namespace detail

/// Writes `records` (time order, strictly increasing at the millisecond) as an RTKLIB .pos
/// file in GPST with every column (see the file comment for the digits kept). Throws
/// std::invalid_argument, before writing, for a value the reader would refuse (non-finite,
/// outside its bounds, a time outside 1980-2200 or not after the previous one at 1 ms);
/// std::runtime_error when the file cannot be written.
inline void write_rtklib_pos(const std::filesystem::path& path, std::span<const RtklibPosRecord> records,
                             const RtklibPosWriteOptions& opt = {}) {
  auto bad = [](std::size_t i, std::string what) {
    throw std::invalid_argument(cat("write_rtklib_pos: record ", i, ": ", what));
  };
  std::string text;
  for (const auto& c : opt.comments) text += "% " + c + "\n";
  text += "%  GPST                  latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)  sdne(m)"
          "  sdeu(m)  sdun(m) age(s)  ratio";
  if (opt.velocity) text += "    vn(m/s)    ve(m/s)    vu(m/s)      sdvn      sdve      sdvu     sdvne     sdveu     sdvun";
  text += '\n';
  constexpr double first_ms = 315'532'800'000.0, end_ms = 7'258'118'400'000.0;  // 1980-01-01, 2200-01-01
  long long previous_ms = -1;
  char buf[512];
  for (std::size_t i = 0; i < records.size(); ++i) {
    const auto& r = records[i];
    if (!(std::isfinite(r.t) && r.t * 1000.0 >= first_ms && r.t * 1000.0 < end_ms)) bad(i, cat("time ", r.t, " s outside 1980-2200"));
    const long long ms = std::llround(r.t * 1000.0);
    if (ms <= previous_ms) bad(i, cat("time ", r.t, " s is not after the previous epoch at 1 ms"));
    previous_ms = ms;
    for (const auto& c : detail::kPosColumns) {
      if (!opt.velocity && std::string_view(c.name).starts_with("v")) continue;
      if (!opt.velocity && std::string_view(c.name).starts_with("sdv")) continue;
      const double v = r.*(c.member);
      if (!(v >= c.lo && v <= c.hi)) bad(i, cat(c.name, " is ", v, ", outside [", c.lo, ", ", c.hi, "]"));
    }
    if (r.q < 0 || r.q > 7) bad(i, cat("Q ", r.q, " outside [0, 7]"));
    if (r.ns < 0 || r.ns > 255) bad(i, cat("ns ", r.ns, " outside [0, 255]"));
    int n = std::snprintf(buf, sizeof buf, "%s %14.9f %14.9f %10.4f %3d %3d %8.4f %8.4f %8.4f %8.4f %8.4f %8.4f %6.2f %6.1f",
                          detail::calendar_time(ms).c_str(), r.latitude_deg, r.longitude_deg, r.height_m, r.q, r.ns,
                          r.sdn_m, r.sde_m, r.sdu_m, r.sdne_m, r.sdeu_m, r.sdun_m, r.age_s, r.ratio);
    text.append(buf, static_cast<std::size_t>(n));
    if (opt.velocity) {
      n = std::snprintf(buf, sizeof buf, " %10.5f %10.5f %10.5f %9.5f %9.5f %9.5f %9.5f %9.5f %9.5f", r.vn_mps, r.ve_mps,
                        r.vu_mps, r.sdvn_mps, r.sdve_mps, r.sdvu_mps, r.sdvne_mps, r.sdveu_mps, r.sdvun_mps);
      text.append(buf, static_cast<std::size_t>(n));
    }
    text += '\n';
  }
  std::ofstream os(path, std::ios::binary | std::ios::trunc);
  os.write(text.data(), static_cast<std::streamsize>(text.size()));
  if (!os.flush()) throw std::runtime_error("write_rtklib_pos: cannot write " + path.string());
}

/// The fixes through to_rtklib_pos_record; velocity columns only when every fix has one.
inline void write_rtklib_pos(const std::filesystem::path& path, std::span<const messages::GnssFix> fixes,
                             RtklibPosWriteOptions opt = {}) {
  std::vector<RtklibPosRecord> records;
  records.reserve(fixes.size());
  bool all_velocity = true;
  for (const auto& f : fixes) {
    records.push_back(to_rtklib_pos_record(f));
    all_velocity = all_velocity && f.velocity.has_value();
  }
  opt.velocity = opt.velocity && all_velocity;
  write_rtklib_pos(path, std::span<const RtklibPosRecord>(records), opt);
}

}  // namespace ctxfuse::io

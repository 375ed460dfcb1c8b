// Reader of RTKLIB solution files (.pos) in the lat/lon/height format with GPST calendar time
// ("yyyy/mm/dd hh:mm:ss.sss"), and their conversion to io::GnssFix.
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
#pragma once

#include <ctxfuse/io/messages.hpp>
#include <ctxfuse/io/text.hpp>

#include <Eigen/Core>

#include <chrono>
#include <cmath>
#include <cstddef>
#include <filesystem>
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
  double sdn_m = kUnknown, sde_m = kUnknown, sdu_m = kUnknown;
  double sdne_m = kUnknown, sdeu_m = kUnknown, sdun_m = kUnknown;  // signed square roots
  double age_s = kUnknown, ratio = kUnknown;
  double vn_mps = kUnknown, ve_mps = kUnknown, vu_mps = kUnknown;
  double sdvn_mps = kUnknown, sdve_mps = kUnknown, sdvu_mps = kUnknown;
  double sdvne_mps = kUnknown, sdveu_mps = kUnknown, sdvun_mps = kUnknown;
  std::size_t line = 0;

  bool has_position_sd() const { return std::isfinite(sdn_m) && std::isfinite(sde_m) && std::isfinite(sdu_m); }
  bool has_velocity() const { return std::isfinite(vn_mps) && std::isfinite(ve_mps) && std::isfinite(vu_mps); }
};

struct RtklibPosFile {
  std::vector<RtklibPosRecord> records;
  std::vector<std::string> columns;  // the header's names after the two GPST fields
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
        if (!header.find(required)) file.fail(cat("header has no column ", quote(required)));
      c_q = *header.find("Q");
      c_ns = *header.find("ns");
      have_header = true;
      continue;
    }
    if (!have_header) file.fail("data before the '%  GPST ...' column header");
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
inline GnssFix to_gnss_fix(const RtklibPosRecord& r) {
  using detail::signed_square;
  GnssFix fix;
  fix.t = r.t;
  fix.frame = PositionFrame::geodetic;
  fix.position = {r.latitude_deg, r.longitude_deg, r.height_m};
  const double ne = std::isfinite(r.sdne_m) ? signed_square(r.sdne_m) : 0.0;
  const double eu = std::isfinite(r.sdeu_m) ? signed_square(r.sdeu_m) : 0.0;
  const double un = std::isfinite(r.sdun_m) ? signed_square(r.sdun_m) : 0.0;
  if (r.has_position_sd())
    fix.cov << r.sde_m * r.sde_m, ne, eu,  //
        ne, r.sdn_m * r.sdn_m, un,         //
        eu, un, r.sdu_m * r.sdu_m;
  else
    fix.cov.setConstant(kUnknown);
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
      fix.velocity_cov.setConstant(kUnknown);
  }
  fix.quality = r.q >= 1 && r.q <= 6 ? static_cast<FixQuality>(r.q) : FixQuality::unknown;
  fix.satellites_used = r.ns;
  return fix;
}

inline std::vector<GnssFix> to_gnss_fixes(const RtklibPosFile& file) {
  std::vector<GnssFix> out;
  out.reserve(file.records.size());
  for (const auto& r : file.records) out.push_back(to_gnss_fix(r));
  return out;
}

}  // namespace ctxfuse::io

// NMEA 0183 reader for scene features: GGA (fix, position), GSA (PDOP), GSV (per-satellite
// elevation, azimuth, SNR) for the GP/GL/GA/GB/BD/GQ/GN talkers, RMC/GLL for epoch time.
//
// - Every sentence's checksum is verified; a sentence with a bad or missing checksum, or with a
//   field that does not parse, is counted, its first few problems are kept with their line
//   numbers, and it is skipped. Reading never throws on content; only an unopenable file throws.
// - Epochs: a time-bearing sentence (GGA, RMC, GLL) whose time differs from the current epoch's
//   starts a new epoch; GSA/GSV sentences belong to the epoch of the last time seen (receivers
//   emit them after the time-bearing sentences of the same fix). Time of day wrapping backwards
//   by more than 12 h is taken as midnight, so epoch times keep increasing.
// - NMEA 4.10+ GSV sentences carry a signal id and repeat a satellite once per signal; the
//   reader keeps the L1-band signal (GPS/GLONASS/BeiDou/QZSS id 1, Galileo id 7 = E1) and
//   treats sentences without a signal id as L1. A satellite without elevation or azimuth is
//   skipped (counted); an empty SNR means "in view, not tracked" (NaN).
// - A log cut short: the last epoch is dropped (stats.dropped_incomplete_last_epoch) when it
//   may be incomplete: its GSV sequence stops before its last sentence ("2 of 3"), or the file
//   ends inside a sentence (no newline) not shown to start a new epoch. A cut exactly between
//   two whole sentences cannot be seen; the epoch keeps the sentences it has.
#pragma once

#include <ctxfuse/io/text.hpp>

#include <charconv>
#include <cmath>
#include <cstddef>
#include <fstream>
#include <istream>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace ctxfuse::io::nmea {

enum class GnssSystem { gps = 1, glonass = 2, galileo = 3, beidou = 4, qzss = 5, unknown = 9 };

/// Stable satellite key across epochs: system * 1000 + PRN.
constexpr int satellite_key(GnssSystem system, int prn) { return static_cast<int>(system) * 1000 + prn; }

struct GgaFix {
  double time_of_day_s = std::numeric_limits<double>::quiet_NaN();
  int quality = 0;  // 0 no fix, 1 SPS, 2 DGNSS, 4 RTK fixed, 5 RTK float, 6 dead reckoning
  double latitude_deg = std::numeric_limits<double>::quiet_NaN();
  double longitude_deg = std::numeric_limits<double>::quiet_NaN();
  double altitude_m = std::numeric_limits<double>::quiet_NaN();
  int satellites_used = 0;
  double hdop = std::numeric_limits<double>::quiet_NaN();
  bool has_position() const { return quality > 0 && std::isfinite(latitude_deg) && std::isfinite(longitude_deg); }
};

struct NmeaSatellite {
  GnssSystem system = GnssSystem::unknown;
  int prn = 0;
  double elevation_deg = 0.0;
  double azimuth_deg = 0.0;
  double snr_dbhz = std::numeric_limits<double>::quiet_NaN();
};

struct NmeaEpoch {
  double time_s = std::numeric_limits<double>::quiet_NaN();  // time of day + 86400 * day wraps
  std::optional<GgaFix> gga;
  double pdop = std::numeric_limits<double>::quiet_NaN();
  std::vector<NmeaSatellite> satellites;
};

struct NmeaProblem {
  std::size_t line = 0;
  std::string message;
  std::size_t column = 0;  // 1-based field of the sentence (1 = the address); 0 = the sentence as a whole
};

struct NmeaStats {
  std::size_t lines = 0;
  std::size_t sentences_used = 0;
  std::size_t checksum_failures = 0;
  std::size_t malformed = 0;
  std::size_t ignored = 0;  // valid sentences of types not used here (VTG, TXT, ...)
  std::size_t satellites_without_geometry = 0;
  bool dropped_incomplete_last_epoch = false;
  std::vector<NmeaProblem> first_problems;  // at most kMaxProblems
  static constexpr std::size_t kMaxProblems = 20;
};

struct NmeaLog {
  std::vector<NmeaEpoch> epochs;
  NmeaStats stats;
};

/// True when `line` is "$...*hh" with hh the XOR of the characters between '$' and '*'.
inline bool checksum_ok(std::string_view line) {
  while (!line.empty() && (line.back() == '\r' || line.back() == '\n' || line.back() == ' ')) line.remove_suffix(1);
  if (line.size() < 4 || (line[0] != '$' && line[0] != '!')) return false;
  const auto star = line.rfind('*');
  if (star == std::string_view::npos || star + 3 != line.size()) return false;
  unsigned char sum = 0;
  for (std::size_t i = 1; i < star; ++i) sum ^= static_cast<unsigned char>(line[i]);
  unsigned value = 0;
  const auto hex = line.substr(star + 1, 2);
  const auto [p, ec] = std::from_chars(hex.data(), hex.data() + 2, value, 16);
  return ec == std::errc{} && p == hex.data() + 2 && value == sum;
}

namespace detail {

// The shared parsers of io/text.hpp, as yes/no: this reader counts problems instead of throwing.
inline bool parse_double(std::string_view s, double& out) { return io::parse_real(s, out) == io::NumberError::none; }
inline bool parse_int(std::string_view s, int& out) { return io::parse_integer(s, out) == io::NumberError::none; }

/// hhmmss(.ss) -> seconds of day.
inline bool parse_time_of_day(std::string_view s, double& out) {
  if (s.size() < 6) return false;
  int h = 0, m = 0;
  double sec = 0;
  if (!parse_int(s.substr(0, 2), h) || !parse_int(s.substr(2, 2), m) || !parse_double(s.substr(4), sec)) return false;
  if (h < 0 || h > 23 || m < 0 || m > 59 || sec < 0.0 || sec >= 61.0) return false;
  out = h * 3600.0 + m * 60.0 + sec;
  return true;
}

/// (d)ddmm.mmmm + hemisphere -> signed degrees.
inline bool parse_angle(std::string_view value, std::string_view hemisphere, int degree_digits, double& out) {
  if (value.size() < static_cast<std::size_t>(degree_digits) + 2) return false;
  int deg = 0;
  double minutes = 0;
  if (!parse_int(value.substr(0, degree_digits), deg) || !parse_double(value.substr(degree_digits), minutes)) return false;
  if (minutes < 0.0 || minutes >= 60.0) return false;
  double v = deg + minutes / 60.0;
  if (hemisphere == "S" || hemisphere == "W")
    v = -v;
  else if (hemisphere != "N" && hemisphere != "E")
    return false;
  out = v;
  return true;
}

inline GnssSystem system_of_talker(std::string_view talker) {
  if (talker == "GP") return GnssSystem::gps;
  if (talker == "GL") return GnssSystem::glonass;
  if (talker == "GA") return GnssSystem::galileo;
  if (talker == "GB" || talker == "BD") return GnssSystem::beidou;
  if (talker == "GQ" || talker == "QZ") return GnssSystem::qzss;
  return GnssSystem::unknown;
}

inline int l1_signal_id(GnssSystem s) { return s == GnssSystem::galileo ? 7 : 1; }

class Reader {
 public:
  NmeaLog log;

  /// `complete`: false for a last line without newline; one that fails its checksum is cut.
  void line(std::string_view text, std::size_t line_number, bool complete = true) {
    ++log.stats.lines;
    while (!text.empty() && (text.back() == '\r' || text.back() == '\n' || text.back() == ' ')) text.remove_suffix(1);
    if (text.empty()) return;
    line_no_ = line_number;
    if (!complete && !checksum_ok(text)) cut_in_current_epoch_ = cut_line_is_current_epoch(text);
    if (!checksum_ok(text)) {
      ++log.stats.checksum_failures;
      problem("bad or missing checksum");
      return;
    }
    const auto star = text.rfind('*');
    const auto fields = io::split_fields(text.substr(1, star - 1), io::Separator::comma);
    const std::string_view address = fields[0];
    if (address.size() != 5) {
      ++log.stats.malformed;
      problem(io::cat("address field ", io::quote(address), " is not talker + 3-letter type"), 1);
      return;
    }
    const std::string_view talker = address.substr(0, 2), type = address.substr(2);
    bool ok = true;
    if (type == "GGA")
      ok = gga(fields);
    else if (type == "GSA")
      ok = gsa(fields);
    else if (type == "GSV")
      ok = gsv(talker, fields);
    else if (type == "RMC")
      ok = timed(fields, 1, "RMC");
    else if (type == "GLL")
      ok = timed(fields, 5, "GLL");
    else {
      ++log.stats.ignored;
      return;
    }
    if (ok)
      ++log.stats.sentences_used;
    else
      ++log.stats.malformed;
  }

  NmeaLog finish() {
    if (has_current_ && (gsv_pending_ || cut_in_current_epoch_)) {
      log.stats.dropped_incomplete_last_epoch = true;
      problem(gsv_pending_ ? "the log ends inside the last epoch's GSV sequence: epoch dropped"
                           : "the log ends inside a sentence of the last epoch: epoch dropped");
    } else if (has_current_) {
      log.epochs.push_back(std::move(current_));
    }
    has_current_ = false;
    return std::move(log);
  }

 private:
  void problem(std::string message, std::size_t column = 0) {
    if (log.stats.first_problems.size() < NmeaStats::kMaxProblems)
      log.stats.first_problems.push_back({line_no_, std::move(message), column});
  }
  /// Field `index` of the sentence (0 = the address) did not parse; reported as the 1-based
  /// column of the comma-separated sentence, as every reader of io/ numbers columns.
  bool fail(std::string_view sentence, std::string_view field, const std::vector<std::string_view>& f, std::size_t index) {
    problem(io::cat(sentence, " column ", index + 1, " '", field, "': ", io::quote(f[index]), " does not parse"), index + 1);
    return false;
  }

  /// Whether a cut sentence may belong to the current epoch: yes unless it is shown to start
  /// a new one, a time-bearing sentence whose time (followed by the next field, since a time
  /// cut to "0214" parses as another) differs from the epoch's.
  bool cut_line_is_current_epoch(std::string_view text) const {
    if (!has_current_) return false;
    const auto f = io::split_fields(text.substr(1), io::Separator::comma);
    const auto type = f[0].size() == 5 ? f[0].substr(2) : std::string_view();
    const std::size_t time_field = type == "GLL" ? 5 : 1;
    double tod = 0.0;
    if ((type != "GGA" && type != "RMC" && type != "GLL") || f.size() <= time_field + 1 ||
        !parse_time_of_day(f[time_field], tod))
      return true;
    return std::abs(day_offset_ + tod - current_.time_s) <= 1e-3;
  }

  NmeaEpoch& epoch_for_time(double tod) {
    if (std::isfinite(last_tod_) && tod < last_tod_ - 43200.0) day_offset_ += 86400.0;
    last_tod_ = tod;
    const double t = day_offset_ + tod;
    if (has_current_ && std::isnan(current_.time_s)) {
      current_.time_s = t;
    } else if (!has_current_ || std::abs(current_.time_s - t) > 1e-3) {
      if (has_current_) log.epochs.push_back(std::move(current_));
      gsv_pending_ = false;
      current_ = NmeaEpoch{};
      current_.time_s = t;
      has_current_ = true;
    }
    return current_;
  }
  NmeaEpoch& epoch_untimed() {
    if (!has_current_) {
      current_ = NmeaEpoch{};
      has_current_ = true;
    }
    return current_;
  }

  bool timed(const std::vector<std::string_view>& f, std::size_t time_field, std::string_view name) {
    if (f.size() <= time_field) {
      problem(io::cat(name, ": too few fields"));
      return false;
    }
    if (f[time_field].empty()) return true;  // no time yet (receiver cold start): nothing to learn
    double tod = 0;
    if (!parse_time_of_day(f[time_field], tod)) return fail(name, "time", f, time_field);
    epoch_for_time(tod);
    return true;
  }

  bool gga(const std::vector<std::string_view>& f) {
    if (f.size() < 10) {
      problem(io::cat("GGA: ", f.size(), " fields, expected at least 10"));
      return false;
    }
    GgaFix fix;
    if (!parse_time_of_day(f[1], fix.time_of_day_s)) return fail("GGA", "time", f, 1);
    if (!parse_int(f[6], fix.quality) || fix.quality < 0 || fix.quality > 9) return fail("GGA", "quality", f, 6);
    if (fix.quality > 0) {
      if (!parse_angle(f[2], f[3], 2, fix.latitude_deg) || std::abs(fix.latitude_deg) > 90.0)
        return fail("GGA", "latitude", f, 2);
      if (!parse_angle(f[4], f[5], 3, fix.longitude_deg) || std::abs(fix.longitude_deg) > 180.0)
        return fail("GGA", "longitude", f, 4);
      if (!f[9].empty() && !parse_double(f[9], fix.altitude_m)) return fail("GGA", "altitude", f, 9);
    }
    if (!f[7].empty() && !parse_int(f[7], fix.satellites_used)) return fail("GGA", "satellites", f, 7);
    if (!f[8].empty() && !parse_double(f[8], fix.hdop)) return fail("GGA", "hdop", f, 8);
    epoch_for_time(fix.time_of_day_s).gga = fix;
    return true;
  }

  bool gsa(const std::vector<std::string_view>& f) {
    if (f.size() < 18) {
      problem(io::cat("GSA: ", f.size(), " fields, expected at least 18"));
      return false;
    }
    if (f[15].empty()) return true;  // no fix: no DOP
    double pdop = 0;
    if (!parse_double(f[15], pdop) || pdop <= 0.0) return fail("GSA", "pdop", f, 15);
    // All GSA sentences of an epoch repeat the combined PDOP; u-blox prints 99.99 without a fix.
    epoch_untimed().pdop = pdop >= 99.0 ? std::numeric_limits<double>::quiet_NaN() : pdop;
    return true;
  }

  bool gsv(std::string_view talker, const std::vector<std::string_view>& f) {
    if (f.size() < 4) {
      problem("GSV: too few fields");
      return false;
    }
    const std::size_t rest = f.size() - 4;
    if (rest % 4 != 0 && rest % 4 != 1) {
      problem(io::cat("GSV: ", f.size(), " fields do not form 4-field satellite groups"));
      return false;
    }
    int total = 0, number = 0, in_view = 0;
    if (!parse_int(f[1], total)) return fail("GSV", "number of messages", f, 1);
    if (!parse_int(f[2], number)) return fail("GSV", "message number", f, 2);
    if (!parse_int(f[3], in_view)) return fail("GSV", "satellites in view", f, 3);
    gsv_pending_ = number < total;
    const GnssSystem system = system_of_talker(talker);
    if (rest % 4 == 1) {
      unsigned signal = 0;
      const std::string_view s = f.back();
      const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), signal, 16);
      if (s.size() != 1 || ec != std::errc{} || p != s.data() + s.size()) return fail("GSV", "signal id", f, f.size() - 1);
      if (static_cast<int>(signal) != l1_signal_id(system)) return true;  // another band: same satellites again
    }
    // Parse all groups first so that a malformed sentence adds nothing.
    std::vector<NmeaSatellite> parsed;
    for (std::size_t g = 0; g < rest / 4; ++g) {
      const std::size_t c = 4 + 4 * g;  // the group's first field
      const auto id = f[c], el = f[c + 1], az = f[c + 2], snr = f[c + 3];
      if (id.empty()) continue;  // padding group
      NmeaSatellite sat;
      sat.system = system;
      if (!parse_int(id, sat.prn) || sat.prn <= 0) return fail("GSV", "satellite id", f, c);
      if (el.empty() || az.empty()) {
        ++log.stats.satellites_without_geometry;
        continue;
      }
      if (!parse_double(el, sat.elevation_deg) || std::abs(sat.elevation_deg) > 90.0)
        return fail("GSV", "elevation", f, c + 1);
      if (!parse_double(az, sat.azimuth_deg) || sat.azimuth_deg < 0.0 || sat.azimuth_deg > 360.0)
        return fail("GSV", "azimuth", f, c + 2);
      if (!snr.empty() && (!parse_double(snr, sat.snr_dbhz) || sat.snr_dbhz < 0.0 || sat.snr_dbhz > 99.0))
        return fail("GSV", "snr", f, c + 3);
      parsed.push_back(sat);
    }
    auto& sats = epoch_untimed().satellites;
    for (const auto& sat : parsed) {
      bool replaced = false;
      for (auto& existing : sats)
        if (existing.system == sat.system && existing.prn == sat.prn) {
          existing = sat;
          replaced = true;
        }
      if (!replaced) sats.push_back(sat);
    }
    return true;
  }

  NmeaEpoch current_;
  bool has_current_ = false;
  bool gsv_pending_ = false;           // the last GSV was not the last of its sequence
  bool cut_in_current_epoch_ = false;  // the file ends inside a sentence of the current epoch
  double day_offset_ = 0.0;
  double last_tod_ = std::numeric_limits<double>::quiet_NaN();
  std::size_t line_no_ = 0;
};

}  // namespace detail

inline NmeaLog parse_nmea(std::istream& in) {
  detail::Reader reader;
  std::string line;
  std::size_t n = 0;
  while (std::getline(in, line)) reader.line(line, ++n, !in.eof());
  return reader.finish();
}

/// Reads a file; throws io::ParseError (a std::runtime_error) naming the file when it cannot
/// be opened.
inline NmeaLog read_nmea_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw io::ParseError(path, 0, 0, "", "cannot open NMEA file");
  return parse_nmea(in);
}

/// Horizontal distance [m] between two nearby geodetic points, from the WGS-84 meridian and
/// prime-vertical radii at their mean latitude (error well below a millimetre at < 1 km).
inline double horizontal_distance_m(double lat1_deg, double lon1_deg, double lat2_deg, double lon2_deg) {
  constexpr double a = 6378137.0, f = 1.0 / 298.257223563, e2 = f * (2.0 - f);
  const double deg = std::numbers::pi / 180.0;
  const double lat = 0.5 * (lat1_deg + lat2_deg) * deg;
  const double s = std::sin(lat);
  const double w = std::sqrt(1.0 - e2 * s * s);
  const double meridian = a * (1.0 - e2) / (w * w * w), prime = a / w;
  double dlon = lon1_deg - lon2_deg;
  if (dlon > 180.0) dlon -= 360.0;
  if (dlon < -180.0) dlon += 360.0;
  const double north = (lat1_deg - lat2_deg) * deg * meridian;
  const double east = dlon * deg * prime * std::cos(lat);
  return std::hypot(north, east);
}

}  // namespace ctxfuse::io::nmea

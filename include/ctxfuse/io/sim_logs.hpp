// CSV logs of a drive (imu.csv, gnss.csv, sats.csv, uwb.csv, speed.csv, mag.csv, truth.csv;
// columns in docs/formats.md) and their readers. Readers reject, with the file, line and field
// named: a wrong header, a wrong number of fields, text that is not a number, non-finite
// values, labels out of range and time going backwards. A malformed file never crashes.
#pragma once

#include <Eigen/Core>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "ctxfuse/sim/drive.hpp"

namespace ctxfuse::sim {

/// A log could not be read. line is 1-based (0: the file as a whole); field may be empty.
class LogError : public std::runtime_error {
 public:
  LogError(std::string file, std::size_t line, std::string field, const std::string& problem)
      : std::runtime_error(compose(file, line, field, problem)), file_(std::move(file)), line_(line), field_(std::move(field)) {}
  const std::string& file() const { return file_; }
  std::size_t line() const { return line_; }
  const std::string& field() const { return field_; }

 private:
  static std::string compose(const std::string& file, std::size_t line, const std::string& field, const std::string& problem) {
    std::string s = file;
    if (line > 0) s += ":" + std::to_string(line);
    s += ": ";
    if (!field.empty()) s += "field '" + field + "': ";
    return s + problem;
  }
  std::string file_;
  std::size_t line_;
  std::string field_;
};

/// Everything the log files carry (sensor outputs, per-range/per-satellite labels, truth).
struct DriveLog {
  std::vector<TruthSample> truth;
  std::vector<ImuSample> imu;
  std::vector<GnssEpoch> gnss;  // first_sat/num_sats index into sats; truth-only fields stay zero
  std::vector<SatObservation> sats;
  std::vector<UwbRange> uwb;
  std::vector<SpeedSample> speed;
  std::vector<MagSample> mag;
};

inline constexpr const char* kImuHeader = "t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z";
inline constexpr const char* kGnssHeader = "t,fix,east,north,up,std_h,std_v,num_sats,pdop,hdop,mean_cn0";
inline constexpr const char* kSatsHeader = "t,sat_id,elevation_deg,azimuth_deg,cn0_dbhz,los";
inline constexpr const char* kUwbHeader = "t,anchor_id,anchor_x,anchor_y,anchor_z,range,rssi,rssi_fp,nlos";
inline constexpr const char* kSpeedHeader = "t,speed";
inline constexpr const char* kMagHeader = "t,mag_x,mag_y,mag_z";
inline constexpr const char* kTruthHeader =
    "t,x,y,z,ve,vn,vu,roll,pitch,yaw,wx,wy,wz,fx,fy,fz,speed,region,scene,static";

namespace detail {

/// Writes numbers with 10 significant digits via snprintf ("C" locale formatting, the same
/// bytes whatever the compiler).
class CsvWriter {
 public:
  explicit CsvWriter(std::ostream& os) : os_(os) {}
  CsvWriter& num(double v) {
    char buf[40];
    const int n = std::snprintf(buf, sizeof buf, "%.10g", v);
    sep();
    os_.write(buf, n);
    return *this;
  }
  CsvWriter& integer(long long v) {
    sep();
    os_ << v;
    return *this;
  }
  CsvWriter& vec(const Eigen::Vector3d& v) { return num(v.x()).num(v.y()).num(v.z()); }
  void end() {
    os_ << '\n';
    first_ = true;
  }

 private:
  void sep() {
    if (!first_) os_ << ',';
    first_ = false;
  }
  std::ostream& os_;
  bool first_ = true;
};

/// Splits and parses one CSV file; every failure becomes a LogError naming file/line/field.
class CsvReader {
 public:
  CsvReader(std::istream& in, std::string file, std::string_view header) : in_(in), file_(std::move(file)) {
    std::string line;
    if (!std::getline(in_, line)) throw LogError(file_, 1, "", "empty file: expected the header '" + std::string(header) + "'");
    line_no_ = 1;
    strip_cr(line);
    if (line != header) throw LogError(file_, 1, "", "header is '" + line + "', expected '" + std::string(header) + "'");
    std::string_view h = header;
    while (true) {
      const auto comma = h.find(',');
      names_.emplace_back(h.substr(0, comma));
      if (comma == std::string_view::npos) break;
      h.remove_prefix(comma + 1);
    }
  }

  /// Advances to the next non-empty row; false at the end of the file.
  bool next() {
    while (std::getline(in_, row_)) {
      ++line_no_;
      strip_cr(row_);
      if (row_.empty()) continue;
      fields_.clear();
      std::string_view r = row_;
      while (true) {
        const auto comma = r.find(',');
        fields_.push_back(r.substr(0, comma));
        if (comma == std::string_view::npos) break;
        r.remove_prefix(comma + 1);
      }
      if (fields_.size() != names_.size())
        throw LogError(file_, line_no_, "", "expected " + std::to_string(names_.size()) + " fields, found " + std::to_string(fields_.size()));
      return true;
    }
    return false;
  }

  double number(std::size_t i) const {
    const std::string_view f = trim(fields_[i]);
    double v = 0.0;
    const auto res = std::from_chars(f.data(), f.data() + f.size(), v);
    if (f.empty() || res.ec != std::errc() || res.ptr != f.data() + f.size())
      throw error(i, "'" + std::string(f) + "' is not a number");
    if (!std::isfinite(v)) throw error(i, "value '" + std::string(f) + "' is not finite");
    if (std::abs(v) > 1e12) throw error(i, "value '" + std::string(f) + "' is absurdly large");
    return v;
  }
  long long integer(std::size_t i, long long lo, long long hi) const {
    const std::string_view f = trim(fields_[i]);
    long long v = 0;
    const auto res = std::from_chars(f.data(), f.data() + f.size(), v);
    if (f.empty() || res.ec != std::errc() || res.ptr != f.data() + f.size())
      throw error(i, "'" + std::string(f) + "' is not an integer");
    if (v < lo || v > hi) throw error(i, std::to_string(v) + " is outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return v;
  }
  Eigen::Vector3d vec(std::size_t i) const { return {number(i), number(i + 1), number(i + 2)}; }

  /// Time in column 0; strictly increasing, or non-decreasing when several rows share an epoch.
  double time(bool rows_share_epochs) {
    const double t = number(0);
    if (have_time_ && (rows_share_epochs ? t < last_t_ : t <= last_t_))
      throw error(0, "time " + std::to_string(t) + " is not after the previous row's " + std::to_string(last_t_) +
                         (rows_share_epochs ? " (out of order)" : " (times must increase)"));
    last_t_ = t;
    have_time_ = true;
    return t;
  }

  LogError error(std::size_t i, const std::string& problem) const { return LogError(file_, line_no_, names_[i], problem); }
  LogError error(const std::string& problem) const { return LogError(file_, line_no_, "", problem); }
  const std::string& file() const { return file_; }
  std::size_t line() const { return line_no_; }

 private:
  static void strip_cr(std::string& s) {
    if (!s.empty() && s.back() == '\r') s.pop_back();
  }
  static std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
    return s;
  }
  std::istream& in_;
  std::string file_;
  std::vector<std::string> names_;
  std::string row_;
  std::vector<std::string_view> fields_;
  std::size_t line_no_ = 0;
  double last_t_ = 0.0;
  bool have_time_ = false;
};

}  // namespace detail

// ---- writers ----

inline void write_imu_csv(std::ostream& os, const std::vector<ImuSample>& v) {
  os << kImuHeader << '\n';
  detail::CsvWriter w(os);
  for (const auto& s : v) {
    w.num(s.t).vec(s.gyro).vec(s.accel);
    w.end();
  }
}
inline void write_gnss_csv(std::ostream& os, const std::vector<GnssEpoch>& v) {
  os << kGnssHeader << '\n';
  detail::CsvWriter w(os);
  for (const auto& e : v) {
    w.num(e.t).integer(e.has_fix ? 1 : 0).vec(e.position).num(e.std_horizontal_m).num(e.std_vertical_m);
    w.integer(e.num_sats).num(e.pdop).num(e.hdop).num(e.mean_cn0_dbhz);
    w.end();
  }
}
inline void write_sats_csv(std::ostream& os, const std::vector<SatObservation>& v) {
  os << kSatsHeader << '\n';
  detail::CsvWriter w(os);
  for (const auto& s : v) {
    w.num(s.t).integer(s.sat_id).num(s.elevation_deg).num(s.azimuth_deg).num(s.cn0_dbhz).integer(s.line_of_sight ? 1 : 0);
    w.end();
  }
}
inline void write_uwb_csv(std::ostream& os, const std::vector<UwbRange>& v) {
  os << kUwbHeader << '\n';
  detail::CsvWriter w(os);
  for (const auto& r : v) {
    w.num(r.t).integer(r.anchor_id).vec(r.anchor_position).num(r.range_m).num(r.rssi_dbm).num(r.rssi_first_path_dbm);
    w.integer(r.nlos ? 1 : 0);
    w.end();
  }
}
inline void write_speed_csv(std::ostream& os, const std::vector<SpeedSample>& v) {
  os << kSpeedHeader << '\n';
  detail::CsvWriter w(os);
  for (const auto& s : v) {
    w.num(s.t).num(s.speed_mps);
    w.end();
  }
}
inline void write_mag_csv(std::ostream& os, const std::vector<MagSample>& v) {
  os << kMagHeader << '\n';
  detail::CsvWriter w(os);
  for (const auto& s : v) {
    w.num(s.t).vec(s.field_ut);
    w.end();
  }
}
inline void write_truth_csv(std::ostream& os, const std::vector<TruthSample>& v) {
  os << kTruthHeader << '\n';
  detail::CsvWriter w(os);
  for (const auto& s : v) {
    w.num(s.t).vec(s.position).vec(s.velocity).num(s.roll).num(s.pitch).num(s.yaw).vec(s.angular_rate).vec(s.specific_force);
    w.num(s.speed).integer(static_cast<int>(s.region)).integer(static_cast<int>(s.scene)).integer(s.is_static ? 1 : 0);
    w.end();
  }
}

/// The names of the seven log files, in the order write_drive_logs writes them.
inline const std::vector<std::string>& log_file_names() {
  static const std::vector<std::string> names{"imu.csv", "gnss.csv", "sats.csv", "uwb.csv", "speed.csv", "mag.csv", "truth.csv"};
  return names;
}

/// Writes one log file by name from the drive (used by write_drive_logs and the tests).
inline void write_log(std::ostream& os, const Drive& d, std::string_view name) {
  if (name == "imu.csv") write_imu_csv(os, d.imu);
  else if (name == "gnss.csv") write_gnss_csv(os, d.gnss);
  else if (name == "sats.csv") write_sats_csv(os, d.sats);
  else if (name == "uwb.csv") write_uwb_csv(os, d.uwb);
  else if (name == "speed.csv") write_speed_csv(os, d.speed);
  else if (name == "mag.csv") write_mag_csv(os, d.mag);
  else if (name == "truth.csv") write_truth_csv(os, d.truth);
  else throw std::invalid_argument("sim: unknown log file '" + std::string(name) + "'");
}

/// Writes all seven files into dir (created if needed). Throws std::runtime_error naming
/// the file that could not be written.
inline void write_drive_logs(const Drive& d, const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir.string() + ": cannot create directory: " + ec.message());
  for (const auto& name : log_file_names()) {
    const auto path = dir / name;
    std::ofstream os(path, std::ios::binary);
    if (!os) throw std::runtime_error(path.string() + ": cannot open for writing");
    write_log(os, d, name);
    os.flush();
    if (!os) throw std::runtime_error(path.string() + ": write failed");
  }
}

// ---- readers ----

inline std::vector<ImuSample> read_imu_csv(std::istream& in, const std::string& file) {
  detail::CsvReader r(in, file, kImuHeader);
  std::vector<ImuSample> out;
  while (r.next()) {
    ImuSample s;
    s.t = r.time(false);
    s.gyro = r.vec(1);
    s.accel = r.vec(4);
    out.push_back(s);
  }
  return out;
}

inline std::vector<GnssEpoch> read_gnss_csv(std::istream& in, const std::string& file) {
  detail::CsvReader r(in, file, kGnssHeader);
  std::vector<GnssEpoch> out;
  while (r.next()) {
    GnssEpoch e;
    e.t = r.time(false);
    e.has_fix = r.integer(1, 0, 1) == 1;
    e.position = r.vec(2);
    e.std_horizontal_m = r.number(5);
    e.std_vertical_m = r.number(6);
    e.num_sats = static_cast<int>(r.integer(7, 0, 1000));
    e.pdop = r.number(8);
    e.hdop = r.number(9);
    e.mean_cn0_dbhz = r.number(10);
    if (e.has_fix && (e.std_horizontal_m <= 0.0 || e.std_vertical_m <= 0.0))
      throw r.error(5, "a fix needs positive std_h and std_v");
    if (e.has_fix && e.num_sats < 4) throw r.error(7, "a fix needs at least 4 satellites");
    out.push_back(e);
  }
  return out;
}

inline std::vector<SatObservation> read_sats_csv(std::istream& in, const std::string& file) {
  detail::CsvReader r(in, file, kSatsHeader);
  std::vector<SatObservation> out;
  while (r.next()) {
    SatObservation s;
    s.t = r.time(true);
    s.sat_id = static_cast<int>(r.integer(1, 1, 999));
    s.elevation_deg = r.number(2);
    s.azimuth_deg = r.number(3);
    s.cn0_dbhz = r.number(4);
    s.line_of_sight = r.integer(5, 0, 1) == 1;
    if (s.elevation_deg < -90.0 || s.elevation_deg > 90.0) throw r.error(2, "elevation must be within [-90, 90] deg");
    if (s.azimuth_deg < 0.0 || s.azimuth_deg >= 360.0) throw r.error(3, "azimuth must be within [0, 360) deg");
    if (s.cn0_dbhz < 0.0 || s.cn0_dbhz > 70.0) throw r.error(4, "C/N0 must be within [0, 70] dB-Hz");
    out.push_back(s);
  }
  return out;
}

inline std::vector<UwbRange> read_uwb_csv(std::istream& in, const std::string& file) {
  detail::CsvReader r(in, file, kUwbHeader);
  std::vector<UwbRange> out;
  while (r.next()) {
    UwbRange u;
    u.t = r.time(true);
    u.anchor_id = static_cast<int>(r.integer(1, 0, 1'000'000));
    u.anchor_position = r.vec(2);
    u.range_m = r.number(5);
    u.rssi_dbm = r.number(6);
    u.rssi_first_path_dbm = r.number(7);
    u.nlos = r.integer(8, 0, 1) == 1;
    if (u.range_m < -10.0 || u.range_m > 1e4) throw r.error(5, "range must be within [-10, 10000] m");
    out.push_back(u);
  }
  return out;
}

inline std::vector<SpeedSample> read_speed_csv(std::istream& in, const std::string& file) {
  detail::CsvReader r(in, file, kSpeedHeader);
  std::vector<SpeedSample> out;
  while (r.next()) {
    SpeedSample s;
    s.t = r.time(false);
    s.speed_mps = r.number(1);
    if (s.speed_mps < -100.0 || s.speed_mps > 100.0) throw r.error(1, "speed must be within [-100, 100] m/s");
    out.push_back(s);
  }
  return out;
}

inline std::vector<MagSample> read_mag_csv(std::istream& in, const std::string& file) {
  detail::CsvReader r(in, file, kMagHeader);
  std::vector<MagSample> out;
  while (r.next()) {
    MagSample m;
    m.t = r.time(false);
    m.field_ut = r.vec(1);
    if (m.field_ut.norm() > 1e4) throw r.error(1, "field magnitude above 10000 uT");
    out.push_back(m);
  }
  return out;
}

inline std::vector<TruthSample> read_truth_csv(std::istream& in, const std::string& file) {
  detail::CsvReader r(in, file, kTruthHeader);
  std::vector<TruthSample> out;
  while (r.next()) {
    TruthSample s;
    s.t = r.time(false);
    s.position = r.vec(1);
    s.velocity = r.vec(4);
    s.roll = r.number(7);
    s.pitch = r.number(8);
    s.yaw = r.number(9);
    s.angular_rate = r.vec(10);
    s.specific_force = r.vec(13);
    s.speed = r.number(16);
    s.region = static_cast<Region>(r.integer(17, 0, 2));
    s.scene = static_cast<Scene>(r.integer(18, 0, 2));
    s.is_static = r.integer(19, 0, 1) == 1;
    out.push_back(s);
  }
  return out;
}

namespace detail {
template <class F>
auto read_file(const std::filesystem::path& path, F&& parse) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw LogError(path.string(), 0, "", "cannot open for reading");
  return parse(in, path.string());
}
}  // namespace detail

/// Reads the seven files of write_drive_logs from dir and links every GNSS epoch to its
/// satellites (rows of sats.csv with the epoch's time). Throws LogError.
inline DriveLog read_drive_logs(const std::filesystem::path& dir) {
  DriveLog log;
  log.imu = detail::read_file(dir / "imu.csv", [](std::istream& i, const std::string& f) { return read_imu_csv(i, f); });
  log.gnss = detail::read_file(dir / "gnss.csv", [](std::istream& i, const std::string& f) { return read_gnss_csv(i, f); });
  log.sats = detail::read_file(dir / "sats.csv", [](std::istream& i, const std::string& f) { return read_sats_csv(i, f); });
  log.uwb = detail::read_file(dir / "uwb.csv", [](std::istream& i, const std::string& f) { return read_uwb_csv(i, f); });
  log.speed = detail::read_file(dir / "speed.csv", [](std::istream& i, const std::string& f) { return read_speed_csv(i, f); });
  log.mag = detail::read_file(dir / "mag.csv", [](std::istream& i, const std::string& f) { return read_mag_csv(i, f); });
  log.truth = detail::read_file(dir / "truth.csv", [](std::istream& i, const std::string& f) { return read_truth_csv(i, f); });
  // Satellites belong to the GNSS epoch with the same time; counts must agree.
  std::size_t k = 0;
  const std::string sats_file = (dir / "sats.csv").string();
  for (auto& e : log.gnss) {
    e.first_sat = k;
    int n = 0;
    while (k < log.sats.size() && log.sats[k].t == e.t) {
      ++k;
      ++n;
    }
    if (n != e.num_sats)
      throw LogError(sats_file, e.first_sat + 2, "t",
                     "gnss.csv lists " + std::to_string(e.num_sats) + " satellites at t=" + std::to_string(e.t) + " but sats.csv has " +
                         std::to_string(n));
  }
  if (k != log.sats.size())
    throw LogError(sats_file, k + 2, "t", "time " + std::to_string(log.sats[k].t) + " is not an epoch of gnss.csv");
  return log;
}

}  // namespace ctxfuse::sim

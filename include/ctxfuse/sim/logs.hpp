// The simulator's CSV logs (imu.csv, gnss.csv, sats.csv, uwb.csv, speed.csv, mag.csv,
// truth.csv; columns in docs/formats.md): the writer, and the readers on io/text.hpp.
//
//   write_drive_logs(drive, dir)   the seven files of a simulated drive
//   read_sim_logs(dir)             what a pipeline runs on (messages::SensorLog, no truth) and, apart,
//                                  the truth and labels scoring reads (sim::TruthLog)
//   csv::read_drive_logs(dir)      the files row by row as the simulator's records, truth
//                                  fields and all (sim/records.hpp)
//
// Every double is written in its shortest round-trip form (std::to_chars, independent of any
// locale), so a drive written and read back is bit for bit the drive: read_sim_logs gives
// exactly sensor_log(drive). The readers reject, as io::ParseError naming file:line:column
// and the column's name: a wrong header, a wrong number of fields, text that is not a number,
// non-finite values and magnitudes above 1e12, labels out of range, values outside their
// physical range, time going backwards, and sats.csv rows that do not match gnss.csv's epochs.
#pragma once

#include <Eigen/Core>

#include <charconv>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <limits>
#include <ostream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "ctxfuse/io/text.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/sim/drive.hpp"
#include "ctxfuse/sim/records.hpp"
#include "ctxfuse/sim/streams.hpp"

namespace ctxfuse::sim {

/// Everything the log files carry, row by row (sensor outputs, per-range/per-satellite labels,
/// truth).
struct DriveLog {
  std::vector<TruthSample> truth;
  std::vector<ImuSample> imu;
  std::vector<GnssEpoch> gnss;  // first_sat/num_sats index into sats; truth-only fields stay zero
  std::vector<SatObservation> sats;
  std::vector<UwbRange> uwb;
  std::vector<SpeedSample> speed;
  std::vector<MagSample> mag;
};

/// A simulated drive's logs read back: the sensor streams, and the truth and labels apart.
struct SimLogs {
  messages::SensorLog sensors;
  TruthLog truth;  // truth.csv, the `los` of sats.csv, the `nlos` of uwb.csv; no fix labels
};

namespace csv {

inline constexpr const char* kImuHeader = "t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z";
inline constexpr const char* kGnssHeader = "t,fix,east,north,up,std_h,std_v,num_sats,pdop,hdop,mean_cn0";
inline constexpr const char* kSatsHeader = "t,sat_id,elevation_deg,azimuth_deg,cn0_dbhz,los";
inline constexpr const char* kUwbHeader = "t,anchor_id,anchor_x,anchor_y,anchor_z,range,rssi,rssi_fp,nlos";
inline constexpr const char* kSpeedHeader = "t,speed";
inline constexpr const char* kMagHeader = "t,mag_x,mag_y,mag_z";
inline constexpr const char* kTruthHeader =
    "t,x,y,z,ve,vn,vu,roll,pitch,yaw,wx,wy,wz,fx,fy,fz,speed,region,scene,static";

namespace detail {

/// One CSV row at a time. Numbers go through std::to_chars: the shortest text that reads back
/// to the same double, and no locale (an ostream's imbued locale could group digits or change
/// the decimal point).
class Writer {
 public:
  explicit Writer(std::ostream& os) : os_(os) {}
  Writer& num(double v) { return put(v); }
  Writer& integer(long long v) { return put(v); }
  Writer& vec(const Eigen::Vector3d& v) { return num(v.x()).num(v.y()).num(v.z()); }
  void end() {
    os_.put('\n');
    first_ = true;
  }

 private:
  template <class T>
  Writer& put(T v) {
    char buf[32];  // a shortest double needs at most 24 characters, a long long 20
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    if (!first_) os_.put(',');
    first_ = false;
    os_.write(buf, r.ptr - buf);
    return *this;
  }
  std::ostream& os_;
  bool first_ = true;
};

/// The rows of one log file after its header, split by io/text.hpp; every accessor throws
/// io::ParseError naming file:line:column and the column.
class Rows {
 public:
  Rows(const std::filesystem::path& path, std::string_view header)
      : file_(path), header_(io::split_fields(header, io::Separator::comma)), fields_(file_.name(), &header_) {
    std::string_view line;
    if (!file_.next(line)) throw io::ParseError(file_.name(), 1, 0, "", io::cat("empty file: expected the header ", io::quote(header)));
    if (line != header) file_.fail(io::cat("header is ", io::quote(line), ", expected ", io::quote(header)));
  }

  /// Advances to the next non-blank row; false at the end of the file. The writer ends every
  /// row with a newline, so a last row without one was cut short (a number cut short still
  /// parses): it is not read.
  bool next() {
    if (!io::next_fields(file_, fields_, io::Separator::comma)) return false;
    if (!file_.ended_by_newline()) return false;
    fields_.expect_count(header_.size());
    return true;
  }

  double num(std::size_t i) const { return fields_.real(i, kRules); }
  Eigen::Vector3d vec(std::size_t i) const { return {num(i), num(i + 1), num(i + 2)}; }
  template <class Int>
  Int integer(std::size_t i, Int lo, Int hi) const {
    return fields_.integer<Int>(i, lo, hi);
  }
  bool flag(std::size_t i) const { return integer<int>(i, 0, 1) == 1; }
  /// num(i), which `ok` must accept; otherwise the message names the rule and the value.
  template <class Ok>
  double num_if(std::size_t i, Ok ok, std::string_view rule) const {
    const double v = num(i);
    if (!ok(v)) fail(i, io::cat(rule, " (is ", v, ")"));
    return v;
  }

  /// Time in column 0: strictly increasing, or non-decreasing where several rows share an
  /// epoch (satellites, anchors).
  double time(bool rows_share_epochs) {
    const double t = num(0);
    if (have_time_ && (rows_share_epochs ? t < last_t_ : t <= last_t_))
      fail(0, io::cat("time ", t, " is not after the previous row's ", last_t_,
                  rows_share_epochs ? " (out of order)" : " (times must increase)"));
    last_t_ = t;
    have_time_ = true;
    return t;
  }

  [[noreturn]] void fail(std::size_t i, std::string reason) const { fields_.fail(i, std::move(reason)); }

 private:
  static constexpr io::RealRules kRules{false, 1e12};  // a 1e300 in a drive log is corruption
  io::TextFile file_;
  io::Header header_;
  io::Fields fields_;
  double last_t_ = 0.0;
  bool have_time_ = false;
};

}  // namespace detail

// ---- writers ----

/// The header, then row(writer, x) for each element of v.
template <class T, class Row>
void write_rows(std::ostream& os, std::string_view header, const std::vector<T>& v, Row row) {
  os << header << '\n';
  detail::Writer w(os);
  for (const auto& x : v) {
    row(w, x);
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
  using W = detail::Writer;
  if (name == "imu.csv") {
    write_rows(os, kImuHeader, d.imu, [](W& w, const ImuSample& s) { w.num(s.t).vec(s.gyro).vec(s.accel); });
  } else if (name == "gnss.csv") {
    write_rows(os, kGnssHeader, d.gnss, [](W& w, const GnssEpoch& e) {
      w.num(e.t).integer(e.has_fix ? 1 : 0).vec(e.position).num(e.std_horizontal_m).num(e.std_vertical_m);
      w.integer(e.num_sats).num(e.pdop).num(e.hdop).num(e.mean_cn0_dbhz);
    });
  } else if (name == "sats.csv") {
    write_rows(os, kSatsHeader, d.sats, [](W& w, const SatObservation& s) {
      w.num(s.t).integer(s.sat_id).num(s.elevation_deg).num(s.azimuth_deg).num(s.cn0_dbhz).integer(s.line_of_sight ? 1 : 0);
    });
  } else if (name == "uwb.csv") {
    write_rows(os, kUwbHeader, d.uwb, [](W& w, const UwbRange& r) {
      w.num(r.t).integer(r.anchor_id).vec(r.anchor_position).num(r.range_m).num(r.rssi_dbm).num(r.rssi_first_path_dbm);
      w.integer(r.nlos ? 1 : 0);
    });
  } else if (name == "speed.csv") {
    write_rows(os, kSpeedHeader, d.speed, [](W& w, const SpeedSample& s) { w.num(s.t).num(s.speed_mps); });
  } else if (name == "mag.csv") {
    write_rows(os, kMagHeader, d.mag, [](W& w, const MagSample& s) { w.num(s.t).vec(s.field_ut); });
  } else if (name == "truth.csv") {
    write_rows(os, kTruthHeader, d.truth, [](W& w, const TruthSample& s) {
      w.num(s.t).vec(s.position).vec(s.velocity).num(s.roll).num(s.pitch).num(s.yaw).vec(s.angular_rate).vec(s.specific_force);
      w.num(s.speed).integer(static_cast<int>(s.region)).integer(static_cast<int>(s.scene)).integer(s.is_static ? 1 : 0);
    });
  } else {
    throw std::invalid_argument(io::cat("sim logs: unknown log file ", io::quote(name)));
  }
}

// ---- readers, one per file ----

inline std::vector<ImuSample> read_imu(const std::filesystem::path& path) {
  detail::Rows r(path, kImuHeader);
  std::vector<ImuSample> out;
  while (r.next()) out.push_back({r.time(false), r.vec(1), r.vec(4)});
  return out;
}

inline std::vector<GnssEpoch> read_gnss(const std::filesystem::path& path) {
  detail::Rows r(path, kGnssHeader);
  std::vector<GnssEpoch> out;
  while (r.next()) {
    GnssEpoch e;
    e.t = r.time(false);
    e.has_fix = r.flag(1);
    e.position = r.vec(2);
    e.std_horizontal_m = r.num(5);
    e.std_vertical_m = r.num(6);
    e.num_sats = r.integer<int>(7, 0, 1000);
    e.pdop = r.num(8);
    e.hdop = r.num(9);
    e.mean_cn0_dbhz = r.num(10);
    if (e.has_fix && (e.std_horizontal_m <= 0.0 || e.std_vertical_m <= 0.0))
      r.fail(e.std_horizontal_m <= 0.0 ? 5 : 6, "a fix needs positive std_h and std_v");
    if (e.has_fix && e.num_sats < 4) r.fail(7, "a fix needs at least 4 satellites");
    out.push_back(e);
  }
  return out;
}

inline std::vector<SatObservation> read_sats(const std::filesystem::path& path) {
  detail::Rows r(path, kSatsHeader);
  std::vector<SatObservation> out;
  while (r.next()) {
    SatObservation s;
    s.t = r.time(true);
    s.sat_id = r.integer<int>(1, 1, 999);
    s.elevation_deg = r.num_if(2, [](double v) { return v >= -90.0 && v <= 90.0; }, "elevation must be within [-90, 90] deg");
    s.azimuth_deg = r.num_if(3, [](double v) { return v >= 0.0 && v < 360.0; }, "azimuth must be within [0, 360) deg");
    s.cn0_dbhz = r.num_if(4, [](double v) { return v >= 0.0 && v <= 70.0; }, "C/N0 must be within [0, 70] dB-Hz");
    s.line_of_sight = r.flag(5);
    out.push_back(s);
  }
  return out;
}

inline std::vector<UwbRange> read_uwb(const std::filesystem::path& path) {
  detail::Rows r(path, kUwbHeader);
  std::vector<UwbRange> out;
  while (r.next()) {
    UwbRange u;
    u.t = r.time(true);
    u.anchor_id = r.integer<int>(1, 0, 1'000'000);
    u.anchor_position = r.vec(2);
    u.range_m = r.num_if(5, [](double v) { return v >= -10.0 && v <= 1e4; }, "range must be within [-10, 10000] m");
    u.rssi_dbm = r.num(6);
    u.rssi_first_path_dbm = r.num(7);
    u.nlos = r.flag(8);
    out.push_back(u);
  }
  return out;
}

inline std::vector<SpeedSample> read_speed(const std::filesystem::path& path) {
  detail::Rows r(path, kSpeedHeader);
  std::vector<SpeedSample> out;
  while (r.next()) {
    const double t = r.time(false);
    out.push_back({t, r.num_if(1, [](double v) { return v >= -100.0 && v <= 100.0; }, "speed must be within [-100, 100] m/s")});
  }
  return out;
}

inline std::vector<MagSample> read_mag(const std::filesystem::path& path) {
  detail::Rows r(path, kMagHeader);
  std::vector<MagSample> out;
  while (r.next()) {
    MagSample m;
    m.t = r.time(false);
    m.field_ut = r.vec(1);
    if (m.field_ut.norm() > 1e4) r.fail(1, "field magnitude above 10000 uT");
    out.push_back(m);
  }
  return out;
}

inline std::vector<TruthSample> read_truth(const std::filesystem::path& path) {
  detail::Rows r(path, kTruthHeader);
  std::vector<TruthSample> out;
  while (r.next()) {
    TruthSample s;
    s.t = r.time(false);
    s.position = r.vec(1);
    s.velocity = r.vec(4);
    s.roll = r.num(7);
    s.pitch = r.num(8);
    s.yaw = r.num(9);
    s.angular_rate = r.vec(10);
    s.specific_force = r.vec(13);
    s.speed = r.num(16);
    s.region = static_cast<Region>(r.integer<int>(17, 0, 2));
    s.scene = static_cast<Scene>(r.integer<int>(18, 0, 2));
    s.is_static = r.flag(19);
    out.push_back(s);
  }
  return out;
}

/// Reads the seven files from dir and links every GNSS epoch to its satellites (the rows of
/// sats.csv with the epoch's time, as many as its num_sats). Throws io::ParseError.
inline DriveLog read_drive_logs(const std::filesystem::path& dir) {
  DriveLog log;
  log.imu = read_imu(dir / "imu.csv");
  log.gnss = read_gnss(dir / "gnss.csv");
  log.sats = read_sats(dir / "sats.csv");
  log.uwb = read_uwb(dir / "uwb.csv");
  log.speed = read_speed(dir / "speed.csv");
  log.mag = read_mag(dir / "mag.csv");
  log.truth = read_truth(dir / "truth.csv");
  // Line k + 2 of sats.csv holds row k (after the header); written files have no blank lines.
  const std::string sats_file = (dir / "sats.csv").string();
  std::size_t k = 0;
  for (auto& e : log.gnss) {
    e.first_sat = k;
    int n = 0;
    for (; k < log.sats.size() && log.sats[k].t == e.t; ++k) ++n;
    if (n != e.num_sats)
      throw io::ParseError(sats_file, e.first_sat + 2, 1, "t",
                       io::cat("gnss.csv lists ", e.num_sats, " satellites at t=", e.t, " but sats.csv has ", n));
  }
  if (k != log.sats.size())
    throw io::ParseError(sats_file, k + 2, 1, "t", io::cat("time ", log.sats[k].t, " is not an epoch of gnss.csv"));
  return log;
}

}  // namespace csv

/// Writes all seven files into dir (created if needed). Throws std::runtime_error naming
/// the file that could not be written.
inline void write_drive_logs(const Drive& d, const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(io::cat(dir.string(), ": cannot create directory: ", ec.message()));
  for (const auto& name : csv::log_file_names()) {
    const auto path = dir / name;
    std::ofstream os(path, std::ios::binary);
    if (!os) throw std::runtime_error(io::cat(path.string(), ": cannot open for writing"));
    csv::write_log(os, d, name);
    os.flush();
    if (!os) throw std::runtime_error(io::cat(path.string(), ": write failed"));
  }
}

/// The logs of dir as a recording: sensor messages without truth, exactly sensor_log of
/// the drive that was written, and the truth and labels apart. The logs hold no true range or
/// NLOS bias per range (NaN in the UWB labels) and no fix errors (no fix labels).
inline SimLogs read_sim_logs(const std::filesystem::path& dir) {
  DriveLog rows = csv::read_drive_logs(dir);
  SimLogs out;
  for (const auto& r : rows.uwb)
    out.truth.uwb.push_back({r.t, r.anchor_id, r.nlos, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()});
  for (const auto& s : rows.sats) out.truth.sats.push_back({s.t, s.sat_id, s.line_of_sight});
  out.truth.truth = std::move(rows.truth);
  // The messages come from the simulator's own conversion (sim/streams.hpp) on a drive that
  // holds only the logged streams, so that logs and simulator cannot drift apart.
  Drive d;
  d.imu = std::move(rows.imu);
  d.gnss = std::move(rows.gnss);
  d.sats = std::move(rows.sats);
  d.uwb = std::move(rows.uwb);
  d.speed = std::move(rows.speed);
  d.mag = std::move(rows.mag);
  out.sensors = sensor_log(d);
  return out;
}

}  // namespace ctxfuse::sim

// The GNSS/INS pipeline on one recording: reading a folder (one RTKLIB *.pos, one imu*.csv
// with its .tag, optionally one mag*.csv), the forward pass over io::replay, optionally the
// RTS smoother over its step records, and the trajectory rows. The GNSS fixes (and the
// magnetometer, when asked for) are the filter's only aiding; the same .pos is the RTK
// reference of the evaluation (studies/outage_protocol.hpp), which this file never sees.
#pragma once

#include <filesystem>
#include <functional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "ctxfuse/io/imu_tag.hpp"
#include "ctxfuse/io/mag_csv.hpp"
#include "ctxfuse/io/replay.hpp"
#include "ctxfuse/io/rtklib_pos.hpp"
#include "ctxfuse/pipelines/gins/forward.hpp"

namespace ctxfuse::pipelines::gins {

struct Recording {
  std::vector<messages::ImuSample> imu;  // IMU axes, SI units, stamps as logged (no delay applied)
  std::vector<messages::GnssFix> fixes;
  std::vector<messages::MagSample> mag;  // empty without a mag*.csv (io/mag_csv.hpp: IMU axes, own stamps)
  std::filesystem::path pos_file, imu_file, mag_file;
  io::ImuTimeMapping imu_time;        // how the IMU's ticks became GPST (io/imu_tag.hpp)
  std::size_t imu_partial_lines = 0;  // cut lines the csv reader skipped (a logger's start or stop)
};

/// Reads DIR: exactly one *.pos and one imu*.csv (with imu*.csv.tag beside it), and at most
/// one mag*.csv.
inline Recording read_recording(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::vector<fs::path> pos, csv, mag;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (e.path().extension() == ".pos") pos.push_back(e.path());
    if (name.starts_with("imu") && e.path().extension() == ".csv") csv.push_back(e.path());
    if (name.starts_with("mag") && e.path().extension() == ".csv") mag.push_back(e.path());
  }
  if (mag.size() > 1) throw std::runtime_error(dir.string() + ": expected at most one mag*.csv file, found " + std::to_string(mag.size()));
  auto one = [&](const std::vector<fs::path>& v, const char* what) {
    if (v.size() != 1)
      throw std::runtime_error(dir.string() + ": expected one " + what + " file, found " + std::to_string(v.size()));
    return v.front();
  };
  Recording r;
  r.pos_file = one(pos, "*.pos");
  r.imu_file = one(csv, "imu*.csv");
  const fs::path tag = r.imu_file.string() + ".tag";
  if (!fs::exists(tag)) throw std::runtime_error(r.imu_file.string() + ": no time-tag file " + tag.filename().string());
  r.fixes = io::to_gnss_fixes(io::read_rtklib_pos(r.pos_file));
  const auto log = io::read_imu_csv(r.imu_file);
  r.imu = io::to_imu_samples(log, io::read_time_tag(tag), {}, &r.imu_time);
  r.imu_partial_lines = log.skipped_lines();
  if (!mag.empty()) {
    r.mag_file = mag.front();
    r.mag = io::read_mag_csv(r.mag_file);
  }
  return r;
}

struct RunOptions {
  Installation installation;
  Constraints constraints;
  OutageSchedule outages;       // disabled by default
  double gnss_rate_hz = 0.0;    // 0: every fix
  /// Magnetometer samples (IMU axes, their own stamps: the IMU delay is not added), replayed
  /// with the IMU and fixes; used when constraints.mag is set.
  std::span<const messages::MagSample> mag;
  bool smooth = false;
  std::function<void(double)> progress;  // fraction of the recording done, now and then
};

/// One epoch of the trajectory: the GNSS antenna's position (the point the fixes give).
struct TrajectoryRow {
  double t = 0.0;                                            // GPST, seconds since 1970 (RTKLIB scale)
  Eigen::Vector3d llh = Eigen::Vector3d::Zero();             // lat, lon [rad], height [m] of the antenna
  Eigen::Vector3d velocity_ned = Eigen::Vector3d::Zero();    // [m/s] of the IMU
  Eigen::Vector3d rpy = Eigen::Vector3d::Zero();             // body -> NED roll, pitch, yaw [rad]
  Eigen::Vector3d sd_position = Eigen::Vector3d::Zero();     // N, E, D [m] (IMU point)
  Eigen::Vector3d sd_velocity = Eigen::Vector3d::Zero();     // [m/s]
  Eigen::Vector3d sd_attitude = Eigen::Vector3d::Zero();     // body-frame rotation error [rad]
  bool gnss_used = false;
};

struct RunResult {
  std::vector<TrajectoryRow> forward, smoothed;  // smoothed empty unless asked for
  std::vector<OutageWindow> windows;
  PassCounts counts;
  StaticStats static_start;
  StaticThresholds static_thresholds;  // the static test's, from the static start or the fallback
  double imu_rate_hz = 0.0;  // samples / span of the IMU stream
  bool aligned = false;
  double alignment_time = 0.0;
  models::PlanarAlignment alignment{};  // the (last) alignment: heading source, baseline, sigmas
  std::size_t record_bytes = 0;  // memory of the step records
  Status smooth_status{};
  io::ReplayReport<2> replay;  // streams: GNSS fixes, magnetometer
};

template <class Model>
TrajectoryRow trajectory_row(double t, const eskf::Belief<Model>& b, const Eigen::Vector3d& gnss_lever) {
  using L = typename Model::ErrorLayout;
  const models::NavState x = nav_part<Model>(b.nominal);
  const Eigen::Matrix3d C = x.get<"theta">().toRotationMatrix();
  TrajectoryRow r;
  r.t = t;
  r.llh = earth::GeodeticRetraction::inject(x.get<"p">(), C * gnss_lever);
  r.velocity_ned = x.get<"v">();
  r.rpy = Eigen::Vector3d(std::atan2(C(2, 1), C(2, 2)), -std::asin(std::clamp(C(2, 0), -1.0, 1.0)), models::heading_of(C));
  r.sd_position = L::template cov<"p">(b.cov).diagonal().cwiseMax(0.0).cwiseSqrt();
  r.sd_velocity = L::template cov<"v">(b.cov).diagonal().cwiseMax(0.0).cwiseSqrt();
  r.sd_attitude = L::template cov<"theta">(b.cov).diagonal().cwiseMax(0.0).cwiseSqrt();
  return r;
}

template <class Model = Nav20>
RunResult run(std::span<const messages::ImuSample> imu_raw, std::span<const messages::GnssFix> fixes, const Settings& settings,
              const RunOptions& opt) {
  RunResult out;
  std::vector<messages::ImuSample> imu(imu_raw.begin(), imu_raw.end());
  for (auto& s : imu) s.t += opt.installation.imu_delay_s;
  if (!fixes.empty()) out.windows = outage_windows(opt.outages, fixes.front().t, fixes.back().t);
  ForwardPass<Model> pass(settings, opt.installation, opt.constraints, out.windows, opt.gnss_rate_hz);
  if (!imu.empty()) {
    const double span = imu.back().t - imu.front().t;
    out.imu_rate_hz = span > 0.0 ? static_cast<double>(imu.size() - 1) / span : 0.0;
    const double per_s = opt.constraints.any() ? 1.0 / settings.constraint_interval_s : 0.0;
    pass.reserve(fixes.size() + static_cast<std::size_t>(std::max(0.0, span) * per_s) + 16);
    if (opt.progress) pass.set_progress(opt.progress, imu.front().t, imu.back().t);
  }
  out.replay = io::replay(pass, std::span<const messages::ImuSample>(imu), fixes, opt.mag);
  pass.finish();
  out.counts = pass.counts();
  out.static_start = pass.static_start();
  out.static_thresholds = pass.static_thresholds();
  out.aligned = pass.aligned();
  out.alignment_time = pass.alignment_time();
  out.alignment = pass.alignment();
  if (!out.aligned) return out;
  auto& rec = pass.recorder();
  const auto& used = pass.gnss_used_per_epoch();
  auto rows = [&](std::vector<TrajectoryRow>& dst) {
    dst.reserve(rec.records().size());
    for (std::size_t k = 0; k < rec.records().size(); ++k) {
      dst.push_back(trajectory_row<Model>(rec.records()[k].t, rec.records()[k].posterior, pass.gnss_lever()));
      dst.back().gnss_used = k < used.size() && used[k] != 0;
    }
  };
  rows(out.forward);
  out.record_bytes = rec.memory_bytes();
  if (opt.smooth) {
    out.smooth_status = rec.smooth(pass.model());
    rows(out.smoothed);
  }
  return out;
}

}  // namespace ctxfuse::pipelines::gins

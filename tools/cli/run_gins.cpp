// `ctxfuse run gins --data DIR`: the GNSS/INS error-state pipeline (ctxfuse/pipelines/gins) on
// one recording folder (one RTKLIB *.pos, one imu*.csv with its .tag), with simulated outages,
// GNSS decimation, the platform and its constraints, the installation and RTS smoothing as
// options. Running needs no reference: scoring is apart and optional, against the RTK-fixed
// epochs of --reference FILE (the outage protocol of ctxfuse/studies/gins_outages.hpp with
// --outage, and the whole run), or with --outage alone against the folder's own .pos.
// --out writes the trajectory (the smoothed one with --smooth):
//   gps_s,lat_deg,lon_deg,height_m,vn,ve,vd,roll_deg,pitch_deg,yaw_deg,
//   sd_n,sd_e,sd_d,sd_vn,sd_ve,sd_vd,sd_roll_deg,sd_pitch_deg,sd_yaw_deg,gnss_used
// (GPST seconds on RTKLIB's 1970-based scale; the GNSS antenna's position; velocity NED [m/s];
// 1-sigma N/E/D [m], [m/s], attitude error [deg]). Parsing and formatting only.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include "cli/formatted.hpp"
#include "cli/json.hpp"
#include "cli/options.hpp"
#include "cli/progress.hpp"
#include "cli/run_gins_plots.hpp"
#include "cli/run_registry.hpp"
#include "ctxfuse/studies/gins_outages.hpp"
#include "ctxfuse/instances/gins_nav20.hpp"

namespace ctxfuse::cli {
namespace {

namespace gins = ctxfuse::pipelines::gins;

struct GinsOptions {
  std::string outage, constraints, platform, reference;
  double gnss_rate = 0.0, imu_delay = 0.0;
  bool smooth = false;
  std::vector<double> imu_rpy{0.0, 0.0, 0.0}, imu_lever{0.0, 0.0, 0.0}, gnss_lever{0.0, 0.0, 0.0};
  std::vector<double> imu_noise;  // gyro [deg/s/sqrt(Hz)], accel [m/s^2/sqrt(Hz)]; empty: the settings'
};

// "LEN:PERIOD:START" -> schedule; an empty string when it parses, the problem otherwise.
std::string parse_outage(const std::string& s, gins::OutageSchedule* out) {
  double v[3];
  std::size_t pos = 0;
  for (int i = 0; i < 3; ++i) {
    const std::size_t end = i < 2 ? s.find(':', pos) : s.size();
    if (end == std::string::npos) return "'" + s + "' is not LEN:PERIOD:START (three numbers separated by ':')";
    const std::string part = s.substr(pos, end - pos);
    std::size_t used = 0;
    try {
      v[i] = std::stod(part, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (part.empty() || used != part.size() || !std::isfinite(v[i]))
      return "'" + part + "' in '" + s + "' is not a number (LEN:PERIOD:START, seconds)";
    pos = end + 1;
  }
  if (!(v[0] > 0.0)) return "outage length " + std::to_string(v[0]) + " s must be positive";
  if (!(v[1] >= v[0])) return "outage period must be at least the length (" + s + ")";
  if (!(v[2] >= 0.0)) return "outage start must be >= 0 s after the first GNSS epoch (" + s + ")";
  if (out) *out = {v[0], v[1], v[2], ctxfuse::studies::standard_outages().end_margin};
  return {};
}

std::string parse_constraints(const std::string& s, gins::Constraints* out) {
  gins::Constraints c;
  if (s == "none") {
    if (out) *out = c;
    return {};
  }
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item == "zupt") c.zupt = true;
    else if (item == "zihr") c.zihr = true;
    else if (item == "nhc") c.nhc = true;
    else if (item == "mag") c.mag = true;  // needs DIR's mag*.csv (checked once the folder is read)
    else return "unknown constraint '" + item + "' (any of zupt,zihr,nhc,mag, or none)";
  }
  if (!c.any()) return "empty constraint list (any of zupt,zihr,nhc,mag, or none)";
  if (out) *out = c;
  return {};
}

std::string constraints_name(const gins::Constraints& c) {
  std::string s;
  for (const auto& [on, name] : {std::pair{c.zupt, "zupt"}, {c.zihr, "zihr"}, {c.nhc, "nhc"}, {c.mag, "mag"}})
    if (on) s += (s.empty() ? "" : ",") + std::string(name);
  return s.empty() ? "none" : s;
}

const CLI::Validator kFinite([](std::string& s) {
  std::size_t used = 0;
  double v = NAN;
  try { v = std::stod(s, &used); } catch (const std::exception&) { used = 0; }
  return used == s.size() && std::isfinite(v) ? std::string() : "'" + s + "' is not a finite number";
}, "", "finite");

std::shared_ptr<void> add_options(CLI::App& app) {
  auto o = std::make_shared<GinsOptions>();
  app.add_option("--outage", o->outage, "simulated GNSS outages LEN:PERIOD:START [s] (START after the first GNSS epoch; windows end "
                                        "30 s before the last); scored against the RTK-fixed epochs")
      ->check(CLI::Validator([](std::string& s) { return parse_outage(s, nullptr); }, "LEN:PERIOD:START", "outage"));
  app.add_option("--gnss-rate", o->gnss_rate, "decimate GNSS to HZ (default: every fix)")->check(ctxfuse::cli::kPositiveNumber);
  app.add_option("--constraints", o->constraints,
                 "any of zupt,zihr,nhc,mag (mag: DIR holds a mag*.csv), or none (default: the --platform's, else none)")
      ->check(CLI::Validator([](std::string& s) { return parse_constraints(s, nullptr); }, "LIST", "constraints"));
  app.add_option("--platform", o->platform,
                 "car, pedestrian or robot: the constraints it allows (car, robot: zupt,nhc; pedestrian: zupt) and their "
                 "figures (pipelines/gins/settings.hpp, settings_for); default: a car's figures, no constraints")
      ->check(CLI::IsMember({"car", "pedestrian", "robot"}));
  app.add_option("--reference", o->reference,
                 "an RTKLIB .pos whose RTK-fixed epochs score the run: the outages with --outage, and the whole run "
                 "(default with --outage: DIR's own .pos)")
      ->check(CLI::ExistingFile);
  app.add_flag("--smooth", o->smooth, "RTS-smooth the forward pass (the CSV is then the smoothed trajectory)");
  app.add_option("--imu-rpy", o->imu_rpy, "IMU axes -> body (forward, right, down): roll,pitch,yaw [deg]")
      ->delimiter(',')->expected(3)->check(kFinite);
  app.add_option("--imu-lever", o->imu_lever, "IMU from the system origin: forward,right,down [m]")->delimiter(',')->expected(3)->check(kFinite);
  app.add_option("--gnss-lever", o->gnss_lever, "GNSS antenna from the system origin: forward,right,down [m]")
      ->delimiter(',')->expected(3)->check(kFinite);
  app.add_option("--imu-delay", o->imu_delay, "logging delay added to IMU time [s]")->check(CLI::Range(-10.0, 10.0));
  app.add_option("--imu-noise", o->imu_noise,
                 "white-noise densities GYRO,ACCEL [deg/s/sqrt(Hz), m/s^2/sqrt(Hz)] instead of the pipeline's "
                 "(pipelines/gins/settings.hpp), for sensitivity studies")
      ->delimiter(',')->expected(2)->check(CLI::PositiveNumber);
  return o;
}

Json scores_json(const ctxfuse::studies::OutageErrors& e) {
  Json j;
  j["rms_m"] = e.rms;
  j["max_m"] = e.max;
  j["epochs"] = e.epochs;
  j["unscored_epochs"] = e.unscored;
  Json per = Json::array();
  for (const auto& o : e.outages) {
    Json w;
    w["start"] = o.window.start;
    w["end"] = o.window.end;
    w["epochs"] = o.epochs;
    w["rms_m"] = o.rms;
    w["max_m"] = o.max;
    per.push_back(std::move(w));
  }
  j["outages"] = std::move(per);
  return j;
}

bool write_csv(const std::string& path, const std::vector<gins::TrajectoryRow>& rows, std::ostream& err) {
  std::ofstream os(path);
  os << "gps_s,lat_deg,lon_deg,height_m,vn,ve,vd,roll_deg,pitch_deg,yaw_deg,sd_n,sd_e,sd_d,sd_vn,sd_ve,sd_vd,"
        "sd_roll_deg,sd_pitch_deg,sd_yaw_deg,gnss_used\n";
  const double d = 1.0 / gins::kDeg;
  char buf[512];
  for (const auto& r : rows) {
    std::snprintf(buf, sizeof buf,
                  "%.3f,%.10f,%.10f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%d\n", r.t,
                  r.llh(0) * d, r.llh(1) * d, r.llh(2), r.velocity_ned(0), r.velocity_ned(1), r.velocity_ned(2), r.rpy(0) * d,
                  r.rpy(1) * d, r.rpy(2) * d, r.sd_position(0), r.sd_position(1), r.sd_position(2), r.sd_velocity(0),
                  r.sd_velocity(1), r.sd_velocity(2), r.sd_attitude(0) * d, r.sd_attitude(1) * d, r.sd_attitude(2) * d,
                  r.gnss_used ? 1 : 0);
    os << buf;
  }
  if (!os.flush()) {
    err << "ctxfuse run gins: cannot write " << path << '\n';
    return false;
  }
  return true;
}

int run_gins(const std::shared_ptr<void>& opts, const FolderRunInput& in, std::ostream& err) {
  const auto& o = *static_cast<const GinsOptions*>(opts.get());
  gins::RunOptions ro;
  if (!o.outage.empty()) parse_outage(o.outage, &ro.outages);
  const gins::Platform platform = o.platform == "pedestrian" ? gins::Platform::pedestrian
                                  : o.platform == "robot"    ? gins::Platform::robot
                                                             : gins::Platform::car;
  if (!o.constraints.empty()) parse_constraints(o.constraints, &ro.constraints);
  else if (!o.platform.empty()) ro.constraints = gins::default_constraints(platform);
  if (ro.constraints.nhc && platform == gins::Platform::pedestrian) {
    err << "ctxfuse run gins: constraint 'nhc' holds on a wheeled platform only, not on --platform pedestrian\n";
    return 2;
  }
  ro.gnss_rate_hz = o.gnss_rate;
  ro.smooth = o.smooth;
  ro.installation.imu_rpy_deg = Eigen::Vector3d(o.imu_rpy[0], o.imu_rpy[1], o.imu_rpy[2]);
  ro.installation.imu_lever_m = Eigen::Vector3d(o.imu_lever[0], o.imu_lever[1], o.imu_lever[2]);
  ro.installation.gnss_lever_m = Eigen::Vector3d(o.gnss_lever[0], o.gnss_lever[1], o.gnss_lever[2]);
  ro.installation.imu_delay_s = o.imu_delay;
  gins::Settings settings = gins::settings_for(platform);
  if (o.imu_noise.size() == 2) {
    settings.gyro_noise_density = o.imu_noise[0] * gins::kDeg;
    settings.accel_noise_density = o.imu_noise[1];
  }
  gins::Recording rec;
  gins::RunResult res;
  {
    Progress progress(err, "ctxfuse run gins", 1.0);
    ro.progress = [&](double f) { progress.update(f); };
    try {
      rec = gins::read_recording(in.data_dir);
      if (rec.imu_time.method == io::ImuTimeMapping::Method::nominal) err << "ctxfuse run gins: warning: " << rec.imu_time.why << '\n';
      // Asking for the magnetometer must not run without one and look as if it had.
      if (ro.constraints.mag && rec.mag.empty()) {
        err << "ctxfuse run gins: constraint 'mag' needs a magnetometer stream: no mag*.csv in " << in.data_dir.string() << '\n';
        return 2;
      }
      ro.mag = rec.mag;
      res = gins::run<gins::Nav20>(rec.imu, rec.fixes, settings, ro);
    } catch (const std::exception& e) {
      err << "ctxfuse run gins: " << e.what() << '\n';
      return 1;
    }
  }
  if (!res.aligned) {
    err << formatted("ctxfuse run gins: no dynamic alignment (no receiver velocity and no straight baseline of fixes over %.1f m "
                     "within %.0f s gave the heading within %.1f deg): no trajectory\n",
                     settings.alignment_min_distance_m, settings.alignment_max_span_s, settings.alignment_max_heading_sigma / gins::kDeg);
    return 1;
  }
  const auto& c = res.counts;
  const auto& ss = res.static_start;
  std::ostream& out = in.out;
  const double t0 = rec.fixes.empty() ? 0.0 : rec.fixes.front().t;
  out << formatted("gins on %s: %zu IMU samples (%.2f Hz), %zu fixes; aligned %.2f s after the first fix\n", in.data_dir.string().c_str(),
                   rec.imu.size(), res.imu_rate_hz, rec.fixes.size(), res.alignment_time - t0);
  out << formatted("  GNSS used %zu, withheld %zu, decimated %zu, gated %zu (released %zu); velocity %zu (gated %zu, released %zu)\n",
                   c.gnss_used, c.gnss_withheld, c.gnss_decimated, c.gnss_gated, c.gnss_released, c.velocity_used, c.velocity_gated,
                   c.velocity_released);
  out << formatted("  ZUPT %zu (gated %zu), ZIHR %zu (%zu), NHC %zu (%zu), mag %zu (%zu); static samples %zu\n", c.zupt, c.zupt_gated,
                   c.zihr, c.zihr_gated, c.nhc, c.nhc_gated, c.mag, c.mag_gated, c.static_samples);
  if (c.imu_losses > 0)
    out << formatted("  IMU gaps past %.1f s: %zu (re-aligned after %zu)\n", settings.imu_max_unmeasured_s, c.imu_losses, c.realignments);
  Json doc;
  doc["pipeline_name"] = "gins";
  doc["data"] = in.data_dir.string();
  doc["platform"] = o.platform.empty() ? "car (default)" : o.platform;
  doc["constraints"] = constraints_name(ro.constraints);
  doc["gnss_rate_hz"] = o.gnss_rate;
  doc["smooth"] = o.smooth;
  doc["outage"] = o.outage;
  doc["imu_samples"] = rec.imu.size();
  doc["imu_rate_hz"] = res.imu_rate_hz;
  doc["fixes"] = rec.fixes.size();
  doc["alignment_after_first_fix_s"] = res.alignment_time - t0;
  {
    const auto& al = res.alignment;
    Json a;
    a["time_after_first_fix_s"] = res.alignment_time - t0;
    a["heading_source"] = models::name_of(al.source);
    a["heading_deg"] = al.heading / gins::kDeg;
    a["heading_sigma_deg"] = std::sqrt(al.heading_var) / gins::kDeg;
    a["baseline_m"] = al.baseline_m;
    a["baseline_s"] = al.baseline_s;
    a["speed_mps"] = al.velocity.norm();
    a["levelled_on_static_start"] = ss.samples > 0;
    doc["alignment"] = std::move(a);
  }
  {
    Json drops;
    auto stream = [](const io::StreamReport& r) {
      Json j;
      j["delivered"] = r.delivered;
      j["non_finite"] = r.non_finite;
      j["backwards"] = r.backwards;
      j["repeated"] = r.repeated;
      j["duplicate"] = r.duplicate;
      j["beyond_imu"] = r.beyond_imu;
      return j;
    };
    drops["imu"] = stream(res.replay.imu);
    drops["gnss"] = stream(res.replay.streams[0]);
    drops["mag"] = stream(res.replay.streams[1]);
    doc["streams"] = std::move(drops);
  }
  doc["epochs"] = res.forward.size();
  doc["record_bytes"] = res.record_bytes;
  {
    Json it;
    it["method"] = io::to_string(rec.imu_time.method);
    it["scale_ppm"] = rec.imu_time.scale_ppm;
    it["bound_ppm"] = rec.imu_time.tolerance_ppm;
    it["csv_span_s"] = rec.imu_time.csv_span_s;
    it["tag_span_s"] = rec.imu_time.tag_span_s;
    it["partial_lines"] = rec.imu_partial_lines;
    it["why"] = rec.imu_time.why;
    doc["imu_time_mapping"] = std::move(it);
  }
  Json counts;
  for (const auto& [k, v] : {std::pair{"gnss_used", c.gnss_used}, {"gnss_withheld", c.gnss_withheld}, {"gnss_decimated", c.gnss_decimated},
                             {"gnss_gated", c.gnss_gated}, {"gnss_released", c.gnss_released}, {"velocity_used", c.velocity_used},
                             {"velocity_gated", c.velocity_gated}, {"velocity_released", c.velocity_released},
                             {"imu_losses", c.imu_losses}, {"realignments", c.realignments}, {"zupt", c.zupt},
                             {"zupt_gated", c.zupt_gated}, {"zihr", c.zihr},
                             {"zihr_gated", c.zihr_gated}, {"nhc", c.nhc}, {"nhc_gated", c.nhc_gated}, {"mag", c.mag},
                             {"mag_gated", c.mag_gated}, {"static_samples", c.static_samples},
                             {"static_but_moving", c.static_but_moving}, {"imu_refused", c.imu_refused},
                             {"filter_failures", c.filter_failures}})
    counts[k] = v;
  doc["counts"] = std::move(counts);
  Json st;
  st["samples"] = ss.samples;
  st["duration_s"] = ss.duration_s;
  st["allan_differences"] = ss.allan_differences;
  const double d = 1.0 / gins::kDeg;
  for (const auto& [k, v, scale] : {std::tuple{"gyro_std_dps", ss.gyro_std, d}, {"gyro_mean_dps", ss.gyro_mean, d},
                                    {"accel_std_mps2", ss.accel_std, 1.0}, {"accel_mean_mps2", ss.accel_mean, 1.0},
                                    {"gyro_allan_1s_dps", ss.gyro_allan_1s, d}, {"accel_allan_1s_mps2", ss.accel_allan_1s, 1.0}}) {
    Json a = Json::array();
    for (int i = 0; i < 3; ++i) a.push_back(v(i) * scale);
    st[k] = std::move(a);
  }
  st["window_s"] = ss.window_s;
  st["window_differences"] = ss.window_differences;
  Json aw = Json::array();
  for (int i = 0; i < 3; ++i) aw.push_back(ss.gyro_allan_window(i) * d);
  st["gyro_allan_window_dps"] = std::move(aw);
  st["f_window_std_mean_mps2"] = ss.f_window_std_mean;
  st["f_window_std_std_mps2"] = ss.f_window_std_std;
  st["f_windows"] = ss.f_windows;
  doc["static_start"] = std::move(st);
  const auto& th = res.static_thresholds;
  Json thj;
  thj["source"] = th.from_start ? "static start" : "fallback";
  thj["gyro_dps"] = th.gyro * d;
  thj["accel_mps2"] = th.accel;
  Json bias = Json::array();
  for (int i = 0; i < 3; ++i) bias.push_back(th.gyro_bias(i) * d);
  thj["gyro_bias_dps"] = std::move(bias);
  doc["static_thresholds"] = std::move(thj);
  // Scoring, apart from the run: the reference's RTK-fixed epochs (--reference, else with
  // --outage the recording's own .pos).
  ctxfuse::studies::GinsOutageScores sc;
  std::vector<messages::GnssFix> reference;
  if (!o.reference.empty()) {
    try {
      reference = io::to_gnss_fixes(io::read_rtklib_pos(o.reference));
    } catch (const std::exception& e) {
      err << "ctxfuse run gins: warning: reference not read, the run is not scored: " << e.what() << '\n';
    }
  } else if (!res.windows.empty()) {
    reference = rec.fixes;
  }
  if (!res.windows.empty() && !reference.empty()) {
    sc = ctxfuse::studies::score_outages(reference, res);
    out << formatted("  outages %zu (%zu scored, %zu RTK-fixed epochs, %zu before the alignment): horizontal error RMS / max\n",
                     res.windows.size(), sc.outages_scored, sc.forward.epochs, sc.forward.unscored);
    out << formatted("    forward   %7.3f / %7.3f m\n", sc.forward.rms, sc.forward.max);
    doc["forward"] = scores_json(sc.forward);
    if (o.smooth) {
      out << formatted("    smoothed  %7.3f / %7.3f m\n", sc.smoothed.rms, sc.smoothed.max);
      doc["smoothed"] = scores_json(sc.smoothed);
    }
    doc["outages_scored"] = sc.outages_scored;
  }
  if (!o.reference.empty() && !reference.empty()) {
    const auto whole = ctxfuse::studies::score_whole_run(reference, res);
    if (whole.forward.epochs == 0) {
      err << "ctxfuse run gins: warning: the reference " << o.reference << " has no RTK-fixed epoch inside the trajectory's span\n";
    } else {
      out << formatted("  whole run against %s (%zu RTK-fixed epochs): forward %.3f / %.3f m", o.reference.c_str(),
                       whole.forward.epochs, whole.forward.rms, whole.forward.max);
      if (o.smooth) out << formatted(", smoothed %.3f / %.3f m", whole.smoothed.rms, whole.smoothed.max);
      out << " RMS / max\n";
      doc["reference"] = o.reference;
      doc["whole_run"]["forward"] = scores_json(whole.forward);
      if (o.smooth) doc["whole_run"]["smoothed"] = scores_json(whole.smoothed);
    }
  }
  if (o.smooth && !res.smooth_status.accepted()) {
    err << "ctxfuse run gins: the RTS pass failed (" << describe(res.smooth_status.problem) << ")\n";
    return 1;
  }
  if (!in.out_csv.empty() && !write_csv(in.out_csv, o.smooth ? res.smoothed : res.forward, err)) return 1;
  if (!in.json.empty() && !write_json_file(doc, in.json, "run gins", err)) return 1;
  if (!in.plot.empty()) {
    Plotter plotter(in.plot, err);
    if (plotter.available()) plot_gins(plotter, rec.fixes, res, sc);
    plotter.print_written(out);
  }
  return 0;
}

const RegisterRunPipeline reg{{"gins", "GNSS/INS error-state filter (papers B and D) on a recording: outages, constraints, RTS",
                               "one RTKLIB *.pos and one imu*.csv with its .tag, optionally one mag*.csv (RTK-fixed epochs of the .pos to score outages)",
                               add_options, {}, run_gins}};

}  // namespace
}  // namespace ctxfuse::cli

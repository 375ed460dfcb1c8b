// The papers' GNSS/INS schemes on the simulated drive (issue 17 "Simulation"; digest sections
// B and D): (a) GNSS/INS, (b) + RTS, (c) + vehicle constraints, (d) + both, each with a fixed
// GNSS R and with the scene-adaptive R of eq. 20-21 (policies/scene_noise.hpp) fed by the
// trained scene classifier on the simulated satellite epochs (studies/gins_sim_scene.hpp), and
// for reference with the true scenes (an oracle, not a result).
//
// The filter is assembled from the geodetic models directly: InsNavModel<SimplifiedStrapdown>
// (the smartphone paper's mechanisation, 15 states: the simulated IMU is aligned with the
// vehicle at its reference point, so the paper's mounting and lever-arm blocks have nothing to
// estimate) augmented with the odometer's scale error (block "speed_scale", a constant with the
// odometer's data-sheet sigma; without it the wheel-radius error is an along-track drift in the
// garage that the covariance does not know), GNSS position at 1 Hz with a one-tailed
// chi-square gate and the GNSS/INS pipeline's lock-out release (filters/release.hpp: after
// three fixes in a row refused, the next is released with the position's variance widened to
// the gate's boundary), ZUPT + NHC with the odometer's forward speed (and optionally ZIHR) at 10 Hz,
// RTS over 10 Hz records.
//
// Static or moving: the raw-IMU detector (models::StaticDetector with the GNSS/INS
// pipeline's fallback window and thresholds, the paper's cue) and the odometer together (OdometerStaticDecision). The simulator has no engine or road vibration,
// so at constant speed on a straight road the IMU alone reads as static (83 % of the moving
// samples on seed 1, `false_static_share`); ZUPT there drags a moving car to zero speed. A
// wheel that turns says the car moves: static needs the detector and a speed within 3 sigma
// of the odometer's noise of zero.
//
// From the simulator to the filter's frames, nothing fitted: ENU metres about the site
// (GnssConfig latitude/longitude, height 0) to latitude/longitude/height with the site's
// radii; FLU body to forward/right/down; yaw from east to heading from north. The simulator's
// flat site has g = 9.80665 m/s^2, the filter's normal gravity at 24.85 deg is 9.7887: the
// study re-expresses the simulated specific force at the filter's gravity (the vehicle stays
// level, so it is a constant on the body z axis); without it the 0.018 m/s^2 difference is an
// accelerometer bias the simulator did not draw. Noise settings: the simulator's IMU data
// sheet (ImuConfig: white-noise densities, Gauss-Markov bias sigma and tau); scale-factor
// errors (1000 ppm) are not modelled by the filter.
#pragma once

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "ctxfuse/studies/gins_sim_scene.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/filters/release.hpp"
#include "ctxfuse/filters/rts.hpp"
#include "ctxfuse/models/ins_augment.hpp"
#include "ctxfuse/models/ins_motion.hpp"
#include "ctxfuse/models/ins_updates.hpp"
#include "ctxfuse/pipelines/gins/settings.hpp"
#include "ctxfuse/policies/gating.hpp"
#include "ctxfuse/policies/health.hpp"

namespace ctxfuse::studies {

struct GinsSimScheme {
  std::string name;
  bool constraints = false;  // ZUPT while static, NHC + odometer speed while moving
  bool zihr = false;         // heading held over each static period (with the constraints)
  bool smooth = false;       // RTS backward pass
};

struct GinsSimSettings {
  double fixed_sigma_m = 2.0;           // fixed R: the open-sky E_0 of eq. 20
  double gate_probability = 0.999;
  /// The lock-out release of the GNSS/INS pipeline's settings (three refused in a row).
  policies::SourceHealthOptions gate_release = pipelines::gins::Settings{}.gate_release;
  double zupt_sigma = 0.02;             // [m/s]
  double nhc_sigma = 0.1;               // [m/s] lateral / vertical
  double zihr_sigma = 0.1 * 3.14159265358979323846 / 180.0;
  double constraint_interval_s = 0.1;   // also the RTS record interval
  /// Prior sigma of the odometer's scale error; none: the odometer's data sheet
  /// (sim::SpeedConfig::scale_sigma); 0: not estimated (the block stays at zero, which is the
  /// 15-state filter).
  std::optional<double> speed_scale_sigma;
};

/// Static when the raw-IMU detector (models::StaticDetector with the GNSS/INS pipeline's
/// fallback window and thresholds) says so and the odometer's latest speed is within three of
/// its noise sigmas of zero (no odometer: the detector alone). `entered` is true on the first
/// static sample of a static period (ZIHR holds the heading from there).
class OdometerStaticDecision {
 public:
  explicit OdometerStaticDecision(double speed_sigma, const pipelines::gins::Settings& s = {})
      : detector_(s.static_window_s, s.static_gyro_threshold, s.static_accel_threshold), speed_limit_(3.0 * speed_sigma) {}
  bool push(double t, const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel, std::optional<double> speed) {
    imu_static_ = detector_.push(t, gyro, accel);
    const bool now = imu_static_ && (!speed || std::abs(*speed) <= speed_limit_);
    entered_ = now && !static_;
    static_ = now;
    return now;
  }
  bool entered_static() const { return entered_; }
  /// The raw-IMU detector's own verdict on the last sample.
  bool imu_static() const { return imu_static_; }

 private:
  models::StaticDetector detector_;
  double speed_limit_;
  bool imu_static_ = false, static_ = false, entered_ = false;
};

/// Horizontal error statistics [m] over a set of 1 Hz truth epochs.
struct HorizontalErrors {
  std::size_t n = 0;
  double rms = 0.0, p67 = 0.0, p75 = 0.0, max = 0.0;
};

inline HorizontalErrors horizontal_errors(std::vector<double> e) {
  HorizontalErrors h;
  h.n = e.size();
  if (e.empty()) return h;
  double s = 0.0;
  for (double v : e) s += v * v;
  h.rms = std::sqrt(s / static_cast<double>(e.size()));
  std::sort(e.begin(), e.end());
  auto q = [&](double p) { return e[std::min(e.size() - 1, static_cast<std::size_t>(std::ceil(p * static_cast<double>(e.size()))) - 1)]; };
  h.p67 = q(0.67);
  h.p75 = q(0.75);
  h.max = e.back();
  return h;
}

struct GinsSimRun {
  GinsSimScheme scheme;
  std::string noise;  // "fixed", "scene (classifier)", "scene (true)"
  HorizontalErrors all, with_gnss, indoor;  // indoor: the garage, where no fix exists
  int fixes_used = 0, fixes_gated = 0, fixes_released = 0;
  std::size_t rts_bytes = 0;
  bool smoothed = false;  // the RTS pass ran to the first epoch (schemes with smooth)
  double speed_scale = 0.0, speed_scale_sigma = 0.0;  // the forward filter's at the end of the drive
};

/// The simulated drive in the filter's frames.
struct GinsSimDrive {
  std::vector<double> t;                               // IMU stamps
  std::vector<Eigen::Vector3d> gyro, accel;            // FRD rates [rad/s], [m/s^2]
  std::vector<models::NavState> truth;                 // at each IMU stamp (biases zero)
  std::vector<int> region;                             // sim::Region per IMU stamp
  std::vector<double> fix_t;                           // fixes
  std::vector<Eigen::Vector3d> fix_llh;
  std::vector<std::size_t> fix_epoch;                  // index into the GNSS epochs
  std::vector<double> speed_t, speed;                  // odometer
  double speed_noise = 0.05;                           // [m/s] SpeedConfig::noise_mps
  double speed_scale_sigma = 0.01;                     // SpeedConfig::scale_sigma (data sheet)
  double speed_scale_truth = 0.0;                      // the drive's drawn scale error (evaluation only)
  double false_static_share = 0.0;                     // IMU detector static while the truth moves
  double false_static_share_odometer = 0.0;            // OdometerStaticDecision static while moving
};

/// The odometer's latest speed at or before t (none before its first sample); `next` is the
/// caller's cursor into the speed samples, advanced as t grows.
inline std::optional<double> odometer_speed_at(const GinsSimDrive& d, double t, std::size_t& next) {
  while (next < d.speed_t.size() && d.speed_t[next] <= t + 1e-9) ++next;
  if (next == 0) return std::nullopt;
  return d.speed[next - 1];
}

inline GinsSimDrive gins_sim_drive(const sim::Drive& d) {
  GinsSimDrive out;
  const double lat0 = d.config.gnss.latitude_deg * 3.14159265358979323846 / 180.0;
  const double lon0 = d.config.gnss.longitude_deg * 3.14159265358979323846 / 180.0;
  const Eigen::Vector3d origin(lat0, lon0, 0.0);
  auto llh_of = [&](const Eigen::Vector3d& enu) {
    return earth::GeodeticRetraction::inject(origin, Eigen::Vector3d(enu.y(), enu.x(), -enu.z()));
  };
  const double dg = sim::kGravity - earth::normal_gravity(lat0, 0.0);
  out.speed_noise = d.config.speed.noise_mps;
  out.speed_scale_sigma = d.config.speed.scale_sigma;
  out.speed_scale_truth = d.speed_scale_error;
  for (const auto& s : d.speed) {
    out.speed_t.push_back(s.t);
    out.speed.push_back(s.speed_mps);
  }
  OdometerStaticDecision decision(out.speed_noise);
  std::size_t moving = 0, false_static = 0, false_static_odometer = 0, spd = 0;
  for (std::size_t k = 0; k < d.imu.size(); ++k) {
    const auto& s = d.imu[k];
    const auto& tr = d.truth[k];
    out.t.push_back(s.t);
    out.gyro.emplace_back(s.gyro.x(), -s.gyro.y(), -s.gyro.z());
    out.accel.emplace_back(s.accel.x(), -s.accel.y(), -s.accel.z() + dg);
    models::NavState x;
    x.get<"p">() = llh_of(tr.position);
    x.get<"v">() = Eigen::Vector3d(tr.velocity.y(), tr.velocity.x(), -tr.velocity.z());
    x.get<"theta">() = Eigen::Quaterniond(Eigen::AngleAxisd(3.14159265358979323846 / 2.0 - tr.yaw, Eigen::Vector3d::UnitZ()));
    out.truth.push_back(x);
    out.region.push_back(static_cast<int>(tr.region));
    const bool st_odometer = decision.push(s.t, out.gyro.back(), out.accel.back(), odometer_speed_at(out, s.t, spd));
    const bool st = decision.imu_static();
    if (!tr.is_static) {
      ++moving;
      false_static += st ? 1 : 0;
      false_static_odometer += st_odometer ? 1 : 0;
    }
  }
  const double n_moving = static_cast<double>(std::max<std::size_t>(moving, 1));
  out.false_static_share = static_cast<double>(false_static) / n_moving;
  out.false_static_share_odometer = static_cast<double>(false_static_odometer) / n_moving;
  for (std::size_t i = 0; i < d.gnss.size(); ++i) {
    if (!d.gnss[i].has_fix) continue;
    out.fix_t.push_back(d.gnss[i].t);
    out.fix_llh.push_back(llh_of(d.gnss[i].position));
    out.fix_epoch.push_back(i);
  }
  return out;
}

using GinsSimBaseModel = models::InsNavModel<models::SimplifiedStrapdown>;
using GinsSimModel = models::Augmented<GinsSimBaseModel, StateBlock<"speed_scale", 1>>;  // a constant

inline GinsSimModel gins_sim_model(const sim::ImuConfig& c) {
  GinsSimModel m;
  m.base.gyro_noise_density = c.gyro_noise_density;
  m.base.accel_noise_density = c.accel_noise_density;
  // Stationary std sigma of dx = -x/tau dt + q dw: q = sigma sqrt(2 / tau).
  m.base.gyro_bias = models::GaussMarkov{c.gyro_bias_sigma * std::sqrt(2.0 / c.gyro_bias_tau_s), c.gyro_bias_tau_s};
  m.base.accel_bias = models::GaussMarkov{c.accel_bias_sigma * std::sqrt(2.0 / c.accel_bias_tau_s), c.accel_bias_tau_s};
  return m;
}

/// One scheme with one noise policy over the drive; errors at the 1 Hz truth epochs.
template <class NoisePolicy>
GinsSimRun run_gins_sim(const GinsSimDrive& d, const sim::ImuConfig& imu, const GinsSimScheme& scheme,
                        NoisePolicy noise, const std::vector<policies::SceneProbabilities>& probabilities,
                        const GinsSimSettings& s = {}) {
  using S = GinsSimModel::State;
  const GinsSimModel model = gins_sim_model(imu);
  GinsSimRun run;
  run.scheme = scheme;
  eskf::Belief<GinsSimModel> b;
  GinsSimModel::set_base_part(b.nominal, d.truth.front());
  b.nominal.get<"speed_scale">().setZero();
  Vector<GinsSimModel::dim> sd;
  const double deg = 3.14159265358979323846 / 180.0;
  sd << 2, 2, 3, 0.1, 0.1, 0.1, 0.5 * deg, 0.5 * deg, 2 * deg, Eigen::Vector3d::Constant(imu.gyro_bias_sigma),
      Eigen::Vector3d::Constant(imu.accel_bias_sigma), s.speed_scale_sigma.value_or(d.speed_scale_sigma);
  b.cov = sd.cwiseAbs2().asDiagonal();
  const policies::ChiSquareGate gate(s.gate_probability);
  policies::SourceHealth gnss_health(s.gate_release);
  OdometerStaticDecision motion(d.speed_noise);
  models::GnssGeodeticPosition<S> gnss;
  models::ZeroVelocity<S> zupt;
  zupt.sigma = s.zupt_sigma;
  models::Heading<S> zihr;
  zihr.sigma = s.zihr_sigma;
  models::NonHolonomicWithSpeed<S> nhc;
  nhc.sigma_lateral = s.nhc_sigma;
  nhc.sigma_speed = d.speed_noise;
  RtsRecorder<GinsSimModel> rec;
  const int every = std::max(1, static_cast<int>(std::lround(s.constraint_interval_s / (d.t[1] - d.t[0]))));
  if (scheme.smooth) {
    rec.reserve(d.t.size() / static_cast<std::size_t>(every) + 2);
    rec.start(d.t.front(), b);
  }
  std::vector<double> est_err_all;
  std::vector<std::size_t> eval_k;  // IMU indices of the 1 Hz evaluation epochs
  std::vector<std::size_t> eval_record;
  std::vector<Eigen::Vector3d> eval_filtered;
  std::size_t fix = 0, spd = 0;
  double held = 0.0;
  for (std::size_t k = 1; k < d.t.size(); ++k) {
    const double dt = d.t[k] - d.t[k - 1];
    models::BodyIncrements inc;
    inc.dtheta = 0.5 * (d.gyro[k - 1] + d.gyro[k]) * dt;
    inc.dv = 0.5 * (d.accel[k - 1] + d.accel[k]) * dt;
    SquareMatrix<GinsSimModel::dim> F;
    if (eskf::predict(model, b, inc, dt, {}, &F).accepted() && scheme.smooth) rec.predicted(F);
    const std::optional<double> speed = odometer_speed_at(d, d.t[k], spd);
    const bool is_static = motion.push(d.t[k], d.gyro[k], d.accel[k], speed);
    const eskf::Belief<GinsSimModel> prior = b;
    while (fix < d.fix_t.size() && d.fix_t[fix] < d.t[k] - 1e-9) ++fix;
    if (fix < d.fix_t.size() && std::abs(d.fix_t[fix] - d.t[k]) < 1e-6) {
      (void)noise.observe(probabilities[d.fix_epoch[fix]]);  // refused: R stays as it was
      gnss.R = noise.geodetic(d.fix_llh[fix]);
      bool released = false;
      const Status st = eskf::update_or_release<"p">(model, gnss, b, d.fix_llh[fix], gate, gnss_health, d.t[k], &released);
      run.fixes_used += st.accepted() ? 1 : 0;
      run.fixes_gated += st.outcome == Outcome::gated ? 1 : 0;
      run.fixes_released += released ? 1 : 0;
      ++fix;
    }
    const bool tick = k % static_cast<std::size_t>(every) == 0;
    if (scheme.constraints) {
      if (scheme.zihr && motion.entered_static()) held = models::heading_of(b.nominal.get<"theta">().toRotationMatrix());
      if (tick && is_static) {
        (void)eskf::update(model, zupt, b, Vector<3>::Zero(), gate);
        if (scheme.zihr) (void)eskf::update(model, zihr, b, Vector<1>(held), gate);
      } else if (tick && speed) {
        nhc.vehicle.gyro = d.gyro[k];
        (void)eskf::update(model, nhc, b, Vector<3>(*speed, 0.0, 0.0), gate);
      }
    }
    if (scheme.smooth && tick) (void)rec.record(d.t[k], prior, b);
    if (k % (static_cast<std::size_t>(every) * 10) == 0) {
      eval_k.push_back(k);
      eval_record.push_back(scheme.smooth ? rec.records().size() - 1 : 0);
      eval_filtered.push_back(b.nominal.get<"p">());
    }
  }
  run.speed_scale = b.nominal.get<"speed_scale">()(0);
  run.speed_scale_sigma = std::sqrt(b.cov(GinsSimModel::dim - 1, GinsSimModel::dim - 1));
  if (scheme.smooth) {
    run.smoothed = rec.smooth(model).accepted();
    run.rts_bytes = rec.memory_bytes();
  }
  std::vector<double> all, with_gnss, indoor;
  for (std::size_t i = 0; i < eval_k.size(); ++i) {
    const Eigen::Vector3d p = scheme.smooth ? rec.records()[eval_record[i]].posterior.nominal.get<"p">() : eval_filtered[i];
    const double e = earth::GeodeticRetraction::difference(p, d.truth[eval_k[i]].get<"p">()).head<2>().norm();
    all.push_back(e);
    (d.region[eval_k[i]] == static_cast<int>(sim::Region::indoor) ? indoor : with_gnss).push_back(e);
  }
  run.all = horizontal_errors(all);
  run.with_gnss = horizontal_errors(with_gnss);
  run.indoor = horizontal_errors(indoor);
  return run;
}

struct GinsSimStudy {
  std::uint64_t seed = 1;
  double speed_scale_truth = 0.0;    // the odometer's drawn scale error
  double scene_accuracy = 0.0;       // classifier argmax against the true scene, all epochs
  double false_static_share = 0.0;           // the raw-IMU detector alone
  double false_static_share_odometer = 0.0;  // the static decision the schemes use
  std::size_t imu_samples = 0, fixes = 0;
  std::vector<GinsSimRun> runs;
};

/// Every scheme with fixed, classifier and true-scene R on a simulated drive (the scene SVM is
/// trained on the drives of other seeds of the same configuration).
template <class = void>
GinsSimStudy gins_sim_study(const sim::Drive& drive, const GinsSimSettings& s = {}) {
  const sim::DriveConfig& cfg = drive.config;
  const GinsSimDrive d = gins_sim_drive(drive);
  const SceneSamples samples = scene_samples(drive);
  const SceneSvm svm = train_scene_svm_for(cfg);
  const auto p_svm = scene_probabilities(svm, samples);
  const auto p_true = true_scene_probabilities(samples);
  GinsSimStudy out;
  out.seed = cfg.seed;
  out.imu_samples = d.t.size();
  out.speed_scale_truth = d.speed_scale_truth;
  out.fixes = d.fix_t.size();
  out.false_static_share = d.false_static_share;
  out.false_static_share_odometer = d.false_static_share_odometer;
  std::size_t right = 0;
  for (std::size_t i = 0; i < p_svm.size(); ++i)
    right += static_cast<int>(std::max_element(p_svm[i].begin(), p_svm[i].end()) - p_svm[i].begin()) == samples.scene[i];
  out.scene_accuracy = p_svm.empty() ? 0.0 : static_cast<double>(right) / static_cast<double>(p_svm.size());
  const GinsSimScheme schemes[] = {{"(a) GNSS/INS", false, false, false},
                                   {"(b) + RTS", false, false, true},
                                   {"(c) + constraints", true, false, false},
                                   {"(d) + constraints + RTS", true, false, true},
                                   {"(c') + constraints with ZIHR", true, true, false},
                                   {"(d') + constraints with ZIHR + RTS", true, true, true}};
  for (const auto& sc : schemes) {
    GinsSimRun f = run_gins_sim(d, cfg.imu, sc, policies::FixedGnssNoise(s.fixed_sigma_m), p_svm, s);
    f.noise = "fixed";
    out.runs.push_back(f);
    GinsSimRun a = run_gins_sim(d, cfg.imu, sc, policies::SceneAdaptiveGnssNoise(), p_svm, s);
    a.noise = "scene (classifier)";
    out.runs.push_back(a);
    GinsSimRun o = run_gins_sim(d, cfg.imu, sc, policies::SceneAdaptiveGnssNoise(), p_true, s);
    o.noise = "scene (true)";
    out.runs.push_back(o);
  }
  return out;
}

/// The study on the drive that `cfg` simulates.
template <class = void>
GinsSimStudy gins_sim_study(const sim::DriveConfig& cfg, const GinsSimSettings& s = {}) {
  return gins_sim_study(sim::simulate_drive(cfg), s);
}

}  // namespace ctxfuse::studies

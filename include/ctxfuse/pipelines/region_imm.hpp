// The region paper's whole pipeline as a library piece (paper A in docs): per-epoch GNSS
// features -> PSO-SVM + HMM + joint vote -> recognised region -> region-aware IMM over three
// planar IMU-driven EKF sub-models, and the baselines it is compared with (GNSS alone, UWB
// alone, each sub-model alone, federated Kalman filter, plain IMM). Runs on a simulated drive
// (sim/drive.hpp).
//
// Every filter-based estimator gets the same sensors and the same noise settings (Settings):
// IMU at 100 Hz drives the planar model, the no-side-slip constraint (10 Hz; optionally the
// wheel speed too) corrects every filter, GNSS fixes (1 Hz, R from the receiver's reported sigma) and UWB ranges (10 Hz) go
// to the sub-filters that take them. All filters start from the first GNSS fix with the
// heading of the initial alignment (taken from truth, as a static alignment with a
// magnetometer or a previous drive would give it, +/- 2 deg). Estimates are scored at every
// GNSS epoch (1 Hz) against truth, per true region.
//
// Sub-models (paper's EKF-ODR, EKF-I-OTR, EKF-IDR): ODR takes GNSS; I-OTR takes GNSS and UWB,
// each with its noise inflated by `iotr_noise_factor` (the "weighted" mode) and a larger
// process noise; IDR takes UWB. Region-aware routing (proposed method): when the recognised
// region is outdoor no sub-model takes UWB; when it is indoor no sub-model takes GNSS; in
// the transition region every sub-model takes what its sensors provide. The plain IMM takes
// everything everywhere, with the same sub-models and the same fixed transition matrix as
// the prior of the region-adaptive one.
// IMM cycles are 1 s long (mix at each GNSS epoch), the rate of the recognised labels, so
// the transition matrices (fixed and recognised) are per second.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "ctxfuse/classify/hmm.hpp"
#include "ctxfuse/classify/joint.hpp"
#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_train.hpp"
#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/federated.hpp"
#include "ctxfuse/filters/imm.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/models/planar.hpp"
#include "ctxfuse/policies/gating.hpp"
#include "ctxfuse/policies/health.hpp"
#include "ctxfuse/policies/integrity.hpp"
#include "ctxfuse/policies/mixing.hpp"
#include "ctxfuse/sim/drive.hpp"

namespace ctxfuse::pipelines::region_imm {

inline constexpr int kRegions = 3;  // 0 outdoor, 1 transition, 2 indoor

// ---------------------------------------------------------------- region recognition
using Feature = Eigen::Vector2d;  // (TNVS, mean SNR [dB-Hz])

struct FeatureSeries {
  std::vector<double> t;
  std::vector<Feature> x;
  std::vector<int> truth;  // region at the epoch
};

/// Features of every GNSS epoch; an epoch without satellites has mean SNR 0 (what a receiver
/// that tracks nothing reports as its average).
inline FeatureSeries gnss_features(const sim::Drive& d) {
  FeatureSeries f;
  for (const auto& e : d.gnss) {
    f.t.push_back(e.t);
    f.x.emplace_back(static_cast<double>(e.num_sats), e.num_sats > 0 ? e.mean_cn0_dbhz : 0.0);
    f.truth.push_back(static_cast<int>(e.region));
  }
  return f;
}

struct RecogniserOptions {
  // PSO over (log2 C, log2 gamma), 3-fold CV; a small swarm is enough for two parameters.
  classify::SvmTuneOptions tune{.log2_c_min = -5.0, .log2_c_max = 10.0, .log2_gamma_min = -8.0, .log2_gamma_max = 3.0,
                                .folds = 3, .fold_seed = 1, .pso = {.swarm_size = 6, .iterations = 5, .seed = 1}};
  classify::HmmFitOptions hmm{};
};

struct Recogniser {
  classify::SvmModel<2, 3> svm;
  classify::GaussianHmm<kRegions, 2> hmm;
  classify::WeightedVote<kRegions, 2> vote;
  classify::SvmTuneResult tuned;
  std::array<std::array<double, kRegions>, 2> validation_accuracy{};  // [svm, hmm][region]
};

struct Recognition {
  std::vector<int> svm, hmm, joint;
};

inline std::vector<int> svm_labels(const classify::SvmModel<2, 3>& model, const FeatureSeries& f) {
  std::vector<int> out;
  out.reserve(f.x.size());
  for (const auto& x : f.x) {
    classify::SvmPrediction<3> p;
    out.push_back(classify::svm_predict(model, x, p) == classify::SvmStatus::ok ? p.label : -1);
  }
  return out;
}

inline Recognition recognise(const Recogniser& r, const FeatureSeries& f) {
  Recognition out;
  out.svm = svm_labels(r.svm, f);
  out.hmm = classify::viterbi<kRegions, 2>(r.hmm, std::span<const Feature>(f.x)).path;
  out.joint.resize(f.x.size());
  for (std::size_t i = 0; i < f.x.size(); ++i) out.joint[i] = r.vote({out.svm[i], out.hmm[i]});
  return out;
}

/// PSO-SVM (one-vs-rest RBF) and HMM trained on the drives in `train` (the SVM on all their
/// epochs pooled, the HMM on each drive as its own sequence, so that no transition is counted
/// across the seam between two drives); per-region accuracies of both on `validate` give the
/// joint vote's weights. Throws std::invalid_argument when `train` is empty.
inline Recogniser train_recogniser(std::span<const FeatureSeries> train, const FeatureSeries& validate,
                                   const RecogniserOptions& opts = {}) {
  if (train.empty()) throw std::invalid_argument("region_imm: train_recogniser needs at least one training drive");
  Recogniser r;
  std::size_t rows = 0;
  for (const auto& f : train) rows += f.x.size();
  classify::SvmFeatures<2> X(static_cast<Eigen::Index>(rows), 2);
  std::vector<int> labels;
  labels.reserve(rows);
  std::vector<classify::LabelledSequence<2>> sequences;
  for (const auto& f : train) {
    for (std::size_t i = 0; i < f.x.size(); ++i)
      X.row(static_cast<Eigen::Index>(labels.size() + i)) = f.x[i].transpose();
    labels.insert(labels.end(), f.truth.begin(), f.truth.end());
    sequences.push_back({std::span<const Feature>(f.x), std::span<const int>(f.truth)});
  }
  classify::SvmTrainOptions so;
  so.kernel = classify::SvmKernel::rbf;
  so.multiclass = classify::SvmMulticlass::one_vs_rest;
  r.tuned = classify::tune_svm_pso<2, 3>(X, labels, so, opts.tune);
  so.C = r.tuned.C;
  so.gamma = r.tuned.gamma;
  r.svm = classify::train_svm<2, 3>(X, labels, so);
  r.hmm = classify::fit_supervised<kRegions, 2>(std::span<const classify::LabelledSequence<2>>(sequences), opts.hmm);

  Recognition v;
  v.svm = svm_labels(r.svm, validate);
  v.hmm = classify::viterbi<kRegions, 2>(r.hmm, std::span<const Feature>(validate.x)).path;
  r.validation_accuracy[0] = classify::per_region_accuracy<kRegions>(validate.truth, v.svm);
  r.validation_accuracy[1] = classify::per_region_accuracy<kRegions>(validate.truth, v.hmm);
  r.vote = classify::WeightedVote<kRegions, 2>::from_accuracies(r.validation_accuracy);
  return r;
}

/// One training drive.
inline Recogniser train_recogniser(const FeatureSeries& train, const FeatureSeries& validate,
                                   const RecogniserOptions& opts = {}) {
  return train_recogniser(std::span<const FeatureSeries>(&train, 1), validate, opts);
}

/// Which simulated drives train and validate the recogniser for a test drive: the drives of
/// seeds test + 101, + 102 and + 103 (same configuration otherwise) train it, seed test + 202
/// gives the per-region validation accuracies of the joint vote. Three training drives: one
/// drive's 540 epochs leave the SVM's (C, gamma) search free to fit that drive's particular
/// sky (the PSO then runs to the edges of its box and the SVM generalises worse than the HMM).
struct TrainingDrives {
  static constexpr std::uint64_t train_seed_offset = 101, train_drives = 3, validate_seed_offset = 202;
};

/// The recogniser for `test` trained on the drives of TrainingDrives (the demo's and the
/// region study's recogniser).
inline Recogniser train_recogniser_for(const sim::Drive& test, const RecogniserOptions& opts = {}) {
  std::vector<FeatureSeries> train;
  for (std::uint64_t k = 0; k < TrainingDrives::train_drives; ++k) {
    sim::DriveConfig cfg = test.config;
    cfg.seed = test.config.seed + TrainingDrives::train_seed_offset + k;
    train.push_back(gnss_features(sim::simulate_drive(cfg)));
  }
  sim::DriveConfig validate = test.config;
  validate.seed = test.config.seed + TrainingDrives::validate_seed_offset;
  return train_recogniser(std::span<const FeatureSeries>(train), gnss_features(sim::simulate_drive(validate)), opts);
}

/// The HMM's causal region posterior at every epoch (forward filter: p(region_t | features up
/// to t)), what an online system knows; an epoch the filter cannot use (non-finite features,
/// zero likelihood) repeats the previous posterior, and the uniform one before the first.
inline std::vector<Vector<kRegions>> hmm_posteriors(const Recogniser& r, const FeatureSeries& f) {
  std::vector<Vector<kRegions>> out;
  out.reserve(f.x.size());
  classify::HmmForwardFilter<kRegions, 2> filter(r.hmm);
  Vector<kRegions> last = Vector<kRegions>::Constant(1.0 / kRegions);
  for (const auto& x : f.x) {
    if (filter.step(x) == classify::FilterStatus::ok) last = filter.posterior();
    out.push_back(last);
  }
  return out;
}

inline double accuracy(std::span<const int> truth, std::span<const int> predicted) {
  if (truth.size() != predicted.size() || truth.empty()) return 0.0;
  std::size_t ok = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) ok += truth[i] == predicted[i] ? 1 : 0;
  return static_cast<double>(ok) / static_cast<double>(truth.size());
}

// ---------------------------------------------------------------- navigation
struct Settings {
  // Process noise (same model for every filter; per sub-model multipliers below).
  double accel_noise_density = 0.05;  // [m/s^2/sqrt(Hz)] covers the IMU's bias/scale errors left unmodelled
  double gyro_noise_density = 5e-4;   // [rad/s/sqrt(Hz)]
  double gyro_bias_walk = 1e-5;
  double accel_bias_walk = 1e-3;
  std::array<double, 3> mode_process_noise_factor{1.0, 2.0, 1.0};  // ODR, I-OTR, IDR
  // Measurements.
  double uwb_sigma = 0.15;            // [m]
  double uwb_tag_height = 1.0;        // [m] (simulator's tag height)
  double uwb_alone_accel_psd = 1.0;   // [m^2/s^3] UWB-alone constant-velocity tracker
  double uwb_hold_after_s = 1.0;      // UWB alone holds its last position after this long without a range
  double gnss_sigma_floor = 0.5;      // [m] lower bound on the receiver-reported sigma
  // Vehicle constraints, applied at the 10 Hz speed-sample times by every filter alike.
  // Wheel speed (odometer) is off by default: the paper's sub-models use GNSS, UWB and the
  // IMU only, and with an odometer every filter here dead-reckons so well that the methods
  // cannot be told apart (docs/results.md, region_imm). The no-side-slip constraint needs no
  // sensor and keeps the IMU-only dead reckoning of a car from diverging in minutes.
  bool use_speed = false;
  bool use_nhc = true;
  double speed_sigma = 0.1;           // [m/s]
  double lateral_sigma = 0.1;         // [m/s] no-side-slip
  double iotr_noise_factor = 2.0;     // I-OTR's weighting of GNSS and UWB
  // Chi-square gate on every GNSS/UWB update. A tight gate keeps the NLOS ranges out (with
  // 0.999999 they pulled EKF-I-OTR onto the mirror image of its track about the approach anchors
  // on seed 4); the lock-out a tight gate risks after a stretch of dead reckoning (seed 2) is
  // handled by the per-source health below, not by loosening the gate.
  double gate_probability = 0.999;
  // Lock-out recovery (policies/health.hpp): a source whose every measurement was gated for
  // `health.timeout_s` (at least `health.min_rejections` of them) widens the filter's position
  // and velocity covariance by these standard deviations, checked at every GNSS epoch.
  policies::SourceHealthOptions health{};
  double recovery_position_sigma = 2.0;  // [m]
  double recovery_velocity_sigma = 0.5;  // [m/s]
  // Integrity against a wrong solution that no gate can see (policies/integrity.hpp): with
  // two anchors in reach a filter may settle on the mirror image of its track about their
  // line, where their ranges keep being accepted. A snapshot multilateration of one UWB time
  // stamp with at least `integrity_min_anchors` ranges (two more than the unknowns, so that
  // its residual test can see one NLOS range) is checked against every filter that takes UWB;
  // `integrity.consecutive` gross disagreements in a row re-anchor the filter: position from
  // the snapshot, velocity and heading from the run of snapshots (see reanchor()).
  bool uwb_integrity = true;
  int integrity_min_anchors = 4;
  policies::SnapshotIntegrityOptions integrity{};
  double reanchor_position_sigma = 0.5;  // [m] added to the snapshot's own uncertainty
  double reanchor_velocity_sigma = 1.0;  // [m/s]
  double reanchor_heading_sigma = 0.3;   // [rad]
  double reanchor_min_speed = 1.0;       // [m/s] below it the heading is kept
  // Initial uncertainty.
  double init_position_sigma = 3.0, init_velocity_sigma = 0.2, init_heading_sigma_deg = 2.0;
  double init_gyro_bias_sigma = 1e-3, init_accel_bias_sigma = 0.05;
  // IMM.
  double stay_probability = 0.9;      // fixed prior: diagonal, per 1 s cycle
  double prior_weight = 0.5;          // w_p; w_m = 1 - w_p
  double probability_floor = 1e-4;
  // Extension (not in the paper): region IMM whose matrix is also pulled towards the HMM's
  // causal region posterior, P = (1 - lambda) P_m + lambda 1 pi' (policies::PosteriorPull).
  double posterior_pull = 0.3;
};

enum class Estimator { gnss, uwb, odr, iotr, idr, fkf, imm, region_imm, region_imm_posterior };
inline constexpr std::array<Estimator, 9> kAllEstimators{
    Estimator::gnss, Estimator::uwb, Estimator::odr,        Estimator::iotr,
    Estimator::idr,  Estimator::fkf, Estimator::imm,        Estimator::region_imm,
    Estimator::region_imm_posterior};
inline const char* name(Estimator e) {
  switch (e) {
    case Estimator::gnss: return "gnss";
    case Estimator::uwb: return "uwb";
    case Estimator::odr: return "odr";
    case Estimator::iotr: return "iotr";
    case Estimator::idr: return "idr";
    case Estimator::fkf: return "fkf";
    case Estimator::imm: return "imm";
    case Estimator::region_imm: return "region_imm";
    case Estimator::region_imm_posterior: return "region_imm_posterior";
  }
  return "?";
}

/// Estimates at the GNSS epochs (ENU x, y) with the true region of each.
struct Track {
  std::vector<double> t;
  std::vector<Eigen::Vector2d> estimate;
  std::vector<Eigen::Vector2d> truth;
  std::vector<int> region;
  std::vector<int> dominant_mode;  // IMMs only
  // Whether the estimator had a solution of its own at the epoch. Filters always do; GNSS
  // alone only with a fix and UWB alone only while its tracker is locked, and at the other
  // epochs they are scored at the position they held (see errors()).
  std::vector<bool> solution;
  // Times the UWB integrity check re-anchored the filter (Settings::uwb_integrity; IMU-driven
  // filters that take UWB only).
  int integrity_faults = 0;
};

struct GnssTag {};
struct UwbTag {};
struct SpeedTag {};

using L = models::PlanarLayout;
using X = Vector<L::size>;

namespace detail {

inline models::PlanarImuModel process_model(const Settings& s, double factor) {
  models::PlanarImuModel m;
  m.accel_noise_density = s.accel_noise_density * std::sqrt(factor);
  m.gyro_noise_density = s.gyro_noise_density * std::sqrt(factor);
  m.gyro_bias_walk = s.gyro_bias_walk;
  m.accel_bias_walk = s.accel_bias_walk;
  return m;
}

inline models::PlanarImu planar_input(const sim::ImuSample& s) {
  models::PlanarImu u;
  u.yaw_rate = s.gyro.z();
  u.accel = s.accel.head<2>();
  return u;
}

inline Gaussian<L::size> initial_belief(const sim::Drive& d, const Settings& s, double t0, const Eigen::Vector2d& p0) {
  Gaussian<L::size> b;
  b.mean.setZero();
  L::get<"p">(b.mean) = p0;
  const auto k = static_cast<std::size_t>(std::lround(t0 * d.config.imu.rate_hz));
  const auto& tr = d.truth[std::min(k, d.truth.size() - 1)];
  L::get<"v">(b.mean) = tr.velocity.head<2>();
  L::get<"psi">(b.mean)(0) = tr.yaw;
  Vector<L::size> sd;
  const double h = s.init_heading_sigma_deg * std::numbers::pi / 180.0;
  sd << s.init_position_sigma, s.init_position_sigma, s.init_velocity_sigma, s.init_velocity_sigma, h,
      s.init_gyro_bias_sigma, s.init_accel_bias_sigma, s.init_accel_bias_sigma;
  b.cov = sd.cwiseProduct(sd).asDiagonal();
  return b;
}

inline models::PlanarPosition gnss_meas(const sim::GnssEpoch& e, const Settings& s, double factor = 1.0) {
  models::PlanarPosition m;
  const double sd = std::max(e.std_horizontal_m, s.gnss_sigma_floor);
  m.R = SquareMatrix<2>::Identity() * (sd * sd * factor);
  return m;
}
inline models::PlanarRange uwb_meas(const sim::UwbRange& r, const Settings& s, double factor = 1.0) {
  models::PlanarRange m;
  m.anchor = r.anchor_position;
  m.tag_height = s.uwb_tag_height;
  m.sigma = s.uwb_sigma * std::sqrt(factor);
  return m;
}
inline models::PlanarLateralVelocity nhc_meas(const Settings& s, double factor = 1.0) {
  models::PlanarLateralVelocity m;
  m.sigma = s.lateral_sigma * std::sqrt(factor);
  return m;
}
inline models::PlanarBodyVelocity speed_meas(const Settings& s, double factor = 1.0) {
  models::PlanarBodyVelocity m;
  m.forward_sigma = s.speed_sigma * std::sqrt(factor);
  m.lateral_sigma = s.lateral_sigma * std::sqrt(factor);
  return m;
}

/// The GNSS and UWB health of one filter, and the recovery from a lock-out of either.
struct FilterHealth {
  policies::SourceHealth gnss, uwb;
  bool gnss_locked_out = false;  // at the last lockout() that returned true
  explicit FilterHealth(const Settings& s) : gnss(s.health), uwb(s.health) {}
  /// True (and the counts restarted) when either source is locked out at time t.
  bool lockout(double t) {
    gnss_locked_out = gnss.lockout(t);
    if (!gnss_locked_out && !uwb.lockout(t)) return false;
    recovered();
    return true;
  }
  /// Restarts both sources' counts (after a recovery, this filter's own or a wider one).
  void recovered() {
    gnss.recovered();
    uwb.recovered();
  }
  /// The position standard deviation a recovery at GNSS epoch `e` needs to reach the fix from
  /// `p`: a filter that ran away from the fixes has to be able to take them again. Leaving a
  /// garage, NLOS ranges whose bias grew smoothly with the distance from the door passed the
  /// gates as motion and left a velocity error; a fixed 2 m widening then took 20 s of
  /// repeated lock-outs to reach fixes 20-40 m away (scenario "paper", seed 1).
  double reach(const sim::GnssEpoch& e, const Eigen::Vector2d& p) const {
    return gnss_locked_out && e.has_fix ? (Eigen::Vector2d(e.position.head<2>()) - p).norm() : 0.0;
  }
};

/// Recovery after a lock-out: position and velocity uncertainty added, the position's at least
/// `reach` (FilterHealth::reach).
inline void widen(SquareMatrix<L::size>& P, const Settings& s, double reach = 0.0) {
  policies::widen_block<L, "p">(P, std::max(s.recovery_position_sigma, reach));
  policies::widen_block<L, "v">(P, s.recovery_velocity_sigma);
}

/// Walks the drive in time order: IMU predictions at 100 Hz and the measurements stamped at
/// each IMU time (the simulator's rates divide the IMU rate). `sink` gets
/// start(t0, p0), predict(u, dt), speed(sample), uwb(range), gnss(epoch) [cycle boundary],
/// and epoch_done(epoch) after all measurements stamped at that epoch.
template <class Sink>
void replay(const sim::Drive& d, Sink& sink) {
  std::size_t g = 0, w = 0, v = 0;
  // Start at the first fix.
  while (g < d.gnss.size() && !d.gnss[g].has_fix) ++g;
  if (g == d.gnss.size()) throw std::invalid_argument("region_imm: the drive has no GNSS fix to start from");
  const double t0 = d.gnss[g].t;
  sink.start(t0, Eigen::Vector2d(d.gnss[g].position.head<2>()));
  while (w < d.uwb.size() && d.uwb[w].t <= t0 + 1e-9) ++w;
  while (v < d.speed.size() && d.speed[v].t <= t0 + 1e-9) ++v;
  sink.epoch_done(d.gnss[g]);
  ++g;
  std::size_t k = 0;
  while (k + 1 < d.imu.size() && d.imu[k + 1].t <= t0 + 1e-9) ++k;
  for (; k + 1 < d.imu.size(); ++k) {
    const double t = d.imu[k + 1].t;
    sink.predict(planar_input(d.imu[k]), t - d.imu[k].t);
    const bool gnss_now = g < d.gnss.size() && d.gnss[g].t <= t + 1e-9;
    if (gnss_now) sink.cycle_start();
    while (v < d.speed.size() && d.speed[v].t <= t + 1e-9) sink.speed(d.speed[v++]);
    while (w < d.uwb.size() && d.uwb[w].t <= t + 1e-9) sink.uwb(d.uwb[w++]);
    if (gnss_now) {
      if (d.gnss[g].has_fix) sink.gnss(d.gnss[g]);
      sink.epoch_done(d.gnss[g]);
      ++g;
    }
  }
}

inline Eigen::Vector2d truth_at(const sim::Drive& d, double t) {
  const auto k = static_cast<std::size_t>(std::lround(t * d.config.imu.rate_hz));
  return d.truth[std::min(k, d.truth.size() - 1)].position.head<2>();
}

inline void record(Track& tr, const sim::Drive& d, const sim::GnssEpoch& e, const Eigen::Vector2d& p, int mode = -1,
                   bool solution = true) {
  tr.t.push_back(e.t);
  tr.estimate.push_back(p);
  tr.truth.push_back(truth_at(d, e.t));
  tr.region.push_back(static_cast<int>(e.region));
  tr.dominant_mode.push_back(mode);
  tr.solution.push_back(solution);
}

// ---- sinks ----
struct GnssOnly {
  const sim::Drive& d;
  Track track;
  Eigen::Vector2d last = Eigen::Vector2d::Zero();
  void start(double, const Eigen::Vector2d& p0) { last = p0; }
  void predict(const models::PlanarImu&, double) {}
  void cycle_start() {}
  void speed(const sim::SpeedSample&) {}
  void uwb(const sim::UwbRange&) {}
  void gnss(const sim::GnssEpoch& e) { last = e.position.head<2>(); }
  // Without a fix the receiver's last position is all the user has.
  void epoch_done(const sim::GnssEpoch& e) { record(track, d, e, last, -1, e.has_fix); }
};

/// Snapshot multilateration: the horizontal position whose ranges (tag at `tag_height`) best
/// fit `ranges` to the anchors, by Gauss-Newton from the anchors' centroid. Returns nothing
/// when fewer than 3 anchors, when the geometry is degenerate, when it does not converge, or
/// when the RMS range residual exceeds `max_rms` (an NLOS range among them). `cov` gets
/// sigma^2 (J'J)^-1.
struct UwbSnapshot {
  Eigen::Vector2d position;
  Eigen::Matrix2d cov;
};
inline std::optional<UwbSnapshot> multilaterate(std::span<const sim::UwbRange> ranges, double tag_height, double sigma,
                                                double max_rms) {
  if (ranges.size() < 3) return std::nullopt;
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
  for (const auto& r : ranges) p += r.anchor_position.head<2>();
  p /= static_cast<double>(ranges.size());
  // Off the centroid a little: on an anchor the Jacobian row vanishes.
  p += Eigen::Vector2d(0.37, 0.23);
  Eigen::Matrix2d JtJ;
  double rms = 0.0;
  for (int iter = 0; iter < 20; ++iter) {
    JtJ.setZero();
    Eigen::Vector2d Jtr = Eigen::Vector2d::Zero();
    double sq = 0.0;
    for (const auto& r : ranges) {
      const Eigen::Vector3d d(p.x() - r.anchor_position.x(), p.y() - r.anchor_position.y(), tag_height - r.anchor_position.z());
      const double n = d.norm();
      if (!(n > 1e-6)) return std::nullopt;
      const Eigen::Vector2d j = d.head<2>() / n;
      const double res = r.range_m - n;
      JtJ += j * j.transpose();
      Jtr += j * res;
      sq += res * res;
    }
    rms = std::sqrt(sq / static_cast<double>(ranges.size()));
    // A near-singular J'J: anchors (nearly) collinear with the tag, the mirror ambiguity open.
    if (JtJ.determinant() < 1e-3) return std::nullopt;
    const Eigen::Vector2d step = JtJ.ldlt().solve(Jtr);
    p += step;
    if (step.norm() < 1e-6) break;
    if (iter == 19) return std::nullopt;
  }
  if (!p.allFinite() || rms > max_rms) return std::nullopt;
  return UwbSnapshot{p, sigma * sigma * JtJ.inverse()};
}

/// Adds `r` to the ranges of one time stamp, starting a new stamp when `r` has another time.
inline void add_to_stamp(std::vector<sim::UwbRange>& stamp, const sim::UwbRange& r) {
  if (!stamp.empty() && std::abs(stamp.front().t - r.t) > 1e-9) stamp.clear();
  stamp.push_back(r);
}

/// The UWB integrity monitor of one IMU-driven filter (Settings::uwb_integrity): gathers the
/// ranges of one time stamp and, once the stamp is complete (the replay has moved on to the
/// next IMU step), checks their snapshot multilateration against the filter's position.
struct UwbIntegrity {
  using Fault = policies::SnapshotIntegrity<2>::Fault;
  const Settings& s;
  policies::SnapshotIntegrity<2> monitor{s.integrity};
  std::vector<sim::UwbRange> ranges{};  // of one time stamp, one per anchor
  int faults = 0;
  void add(const sim::UwbRange& r) {
    if (s.uwb_integrity) add_to_stamp(ranges, r);
  }
  /// The fault, if the stamp gathered so far completes a run of disagreements with `b`.
  std::optional<Fault> flush(const Gaussian<L::size>& b) {
    if (ranges.empty()) return std::nullopt;
    std::optional<Fault> fault;
    if (static_cast<int>(ranges.size()) >= s.integrity_min_anchors) {
      if (const auto snap = multilaterate(ranges, s.uwb_tag_height, s.uwb_sigma, 3.0 * s.uwb_sigma))
        fault = monitor.check(ranges.front().t, snap->position, snap->cov, L::get<"p">(b.mean),
                              L::cov<"p">(b.cov));
    }
    ranges.clear();
    if (fault) ++faults;
    return fault;
  }
};

/// Re-anchors a belief after an integrity fault: the position is the snapshot's, the velocity
/// the run's mean velocity, the heading that velocity's direction when the vehicle moved
/// faster than `reanchor_min_speed` (kept otherwise); their cross-covariances with everything
/// else are dropped, the sensor biases and their covariance kept. The filter's own velocity
/// and heading are not worth keeping: on a mirror track they are the true ones reflected.
inline void reanchor(Gaussian<L::size>& b, const UwbIntegrity::Fault& f, const Settings& s) {
  constexpr int kinematic = L::size_of<"p">() + L::size_of<"v">() + L::size_of<"psi">();
  static_assert(L::offset<"p">() == 0 && L::offset<"v">() == 2 && L::offset<"psi">() == 4,
                "reanchor assumes p, v, psi lead the layout");
  b.cov.topRows<kinematic>().setZero();
  b.cov.leftCols<kinematic>().setZero();
  L::get<"p">(b.mean) = f.position;
  L::cov<"p">(b.cov) = f.cov + Eigen::Matrix2d::Identity() * (s.reanchor_position_sigma * s.reanchor_position_sigma);
  const double var_v = s.reanchor_velocity_sigma * s.reanchor_velocity_sigma;
  if (f.velocity) {
    L::get<"v">(b.mean) = *f.velocity;
    if (f.velocity->norm() > s.reanchor_min_speed) L::get<"psi">(b.mean)(0) = std::atan2(f.velocity->y(), f.velocity->x());
  }
  L::cov<"v">(b.cov) = Eigen::Matrix2d::Identity() * var_v;
  L::cov<"psi">(b.cov)(0, 0) = s.reanchor_heading_sigma * s.reanchor_heading_sigma;
}

/// UWB alone: the ranges in a constant-velocity EKF (no IMU), as a UWB positioning system
/// runs its own tracker. The track starts from a snapshot multilateration of one epoch's
/// ranges (at least 3 anchors, residuals consistent with line of sight), and is re-anchored
/// to such a snapshot whenever the two disagree (chi-square 0.999 on 2 dof): with only the
/// two approach anchors in reach, ranges cannot tell the track from its mirror image about
/// the anchors' line, and a tracker that once slipped onto the mirror keeps having its
/// ranges accepted there. Lock is lost when no range has arrived for `uwb_hold_after_s` (out
/// of radio range) or when every range has been gated for the health timeout (a lock-out,
/// as policies/health.hpp defines it); without lock the last position is held (what such a
/// system reports when it loses the tag).
struct UwbOnly {
  using Cv = models::ConstantVelocity<L, 2>;
  const sim::Drive& d;
  const Settings& s;
  Track track{};
  std::optional<Ekf<Cv, ChiSquareGate>> f{};
  policies::SourceHealth health{s.health};
  bool locked = false;
  double last_range_t = -1e9;
  Eigen::Vector2d held = Eigen::Vector2d::Zero();
  double now = 0.0;
  std::vector<sim::UwbRange> epoch_ranges{};  // the ranges of the current time stamp so far
  void start(double t0, const Eigen::Vector2d& p0) {
    Cv cv;
    cv.accel_psd = s.uwb_alone_accel_psd;
    Gaussian<L::size> b;
    b.mean.setZero();
    L::get<"p">(b.mean) = p0;
    b.cov = SquareMatrix<L::size>::Identity();
    f.emplace(cv, b, FilterOptions{}, ChiSquareGate(s.gate_probability));
    now = t0;
    held = p0;
  }
  void predict(const models::PlanarImu&, double dt) {
    now += dt;
    (void)f->predict({}, dt);
  }
  void cycle_start() {}
  void speed(const sim::SpeedSample&) {}
  // The integrity check with the chi-square test (0.999, 2 dof) alone and one snapshot
  // enough: a snapshot tracker has no IMU to carry it through an NLOS stamp, so it follows
  // every snapshot that disagrees.
  policies::SnapshotIntegrity<2> mirror_check{{.probability = 0.999, .min_error_m = 0.0, .consecutive = 1}};
  bool disagrees(const UwbSnapshot& snap, double t) {
    const auto& b = f->belief();
    return mirror_check.check(t, snap.position, snap.cov, L::get<"p">(b.mean), L::cov<"p">(b.cov)).has_value();
  }
  void uwb(const sim::UwbRange& r) {
    last_range_t = now;
    add_to_stamp(epoch_ranges, r);
    const auto snap = multilaterate(epoch_ranges, s.uwb_tag_height, s.uwb_sigma, 3.0 * s.uwb_sigma);
    if (snap && (!locked || disagrees(*snap, r.t))) {
      Gaussian<L::size> b = f->belief();
      L::get<"p">(b.mean) = snap->position;
      b.cov = SquareMatrix<L::size>::Identity();
      L::cov<"p">(b.cov) = snap->cov;
      if (!locked) {
        L::get<"v">(b.mean).setZero();
        L::cov<"v">(b.cov) *= 4.0;  // (2 m/s)^2: a vehicle's speed, direction unknown
      } else {
        L::cov<"v">(b.cov) = L::cov<"v">(f->belief().cov);
      }
      f->reset(b);
      locked = true;
      health.recovered();
      return;
    }
    if (!locked) return;
    health.record(r.t, f->update(uwb_meas(r, s), Vector<1>(r.range_m)));
    if (health.lockout(r.t)) locked = false;
  }
  void gnss(const sim::GnssEpoch&) {}
  void epoch_done(const sim::GnssEpoch& e) {
    if (now - last_range_t > s.uwb_hold_after_s) locked = false;
    if (locked) held = L::get<"p">(f->belief().mean);
    record(track, d, e, held, -1, locked);
  }
};

/// One sub-model alone (EKF-ODR / EKF-I-OTR / EKF-IDR).
struct SingleModel {
  const sim::Drive& d;
  const Settings& s;
  bool takes_gnss, takes_uwb;
  double process_factor, meas_factor;
  Track track;
  std::optional<Ekf<models::PlanarImuModel, ChiSquareGate>> f;
  FilterHealth health{s};
  UwbIntegrity integrity{s};
  void start(double t0, const Eigen::Vector2d& p0) {
    f.emplace(process_model(s, process_factor), initial_belief(d, s, t0, p0), FilterOptions{},
              ChiSquareGate(s.gate_probability));
  }
  void predict(const models::PlanarImu& u, double dt) {
    if (const auto fault = integrity.flush(f->belief())) {
      auto b = f->belief();
      reanchor(b, *fault, s);
      f->reset(b);
      health.recovered();
    }
    (void)f->predict(u, dt);
  }
  void cycle_start() {}
  void speed(const sim::SpeedSample& v) {
    if (s.use_speed)
      (void)f->update(speed_meas(s), Vector<2>(v.speed_mps, 0.0));
    else if (s.use_nhc)
      (void)f->update(nhc_meas(s), Vector<1>(0.0));
  }
  void uwb(const sim::UwbRange& r) {
    if (!takes_uwb) return;
    health.uwb.record(r.t, f->update(uwb_meas(r, s, meas_factor), Vector<1>(r.range_m)));
    integrity.add(r);
  }
  void gnss(const sim::GnssEpoch& e) {
    if (takes_gnss) health.gnss.record(e.t, f->update(gnss_meas(e, s, meas_factor), Vector<2>(e.position.head<2>())));
  }
  void epoch_done(const sim::GnssEpoch& e) {
    record(track, d, e, L::get<"p">(f->belief().mean));
    if (health.lockout(e.t)) {
      auto b = f->belief();
      widen(b.cov, s, health.reach(e, L::get<"p">(b.mean)));
      f->reset(b);
    }
  }
};

/// Federated filter: local filter 0 takes GNSS, local filter 1 takes UWB; both take speed
/// with R / beta_i (its share); fusion and reset at every GNSS epoch.
struct Federated {
  const sim::Drive& d;
  const Settings& s;
  Track track;
  std::array<double, 2> beta{0.5, 0.5};
  std::optional<fkf::FederatedFilter<models::PlanarImuModel, 2, ChiSquareGate>> f;
  FilterHealth health{s};
  UwbIntegrity integrity{s};  // against the UWB local filter
  void start(double t0, const Eigen::Vector2d& p0) {
    f.emplace(process_model(s, 1.0), initial_belief(d, s, t0, p0), beta, FilterOptions{}, ChiSquareGate(s.gate_probability));
  }
  void predict(const models::PlanarImu& u, double dt) {
    if (const auto fault = integrity.flush(f->local(1))) {
      auto g = f->global();
      reanchor(g, *fault, s);
      f->reset(g);
      health.recovered();
    }
    (void)f->predict(u, dt);
  }
  void cycle_start() {}
  void speed(const sim::SpeedSample& v) {
    for (int i = 0; i < 2; ++i) {
      const double share = 1.0 / beta[static_cast<std::size_t>(i)];
      if (s.use_speed)
        (void)f->update(i, speed_meas(s, share), Vector<2>(v.speed_mps, 0.0));
      else if (s.use_nhc)
        (void)f->update(i, nhc_meas(s, share), Vector<1>(0.0));
    }
  }
  void uwb(const sim::UwbRange& r) {
    health.uwb.record(r.t, f->update(1, uwb_meas(r, s), Vector<1>(r.range_m)));
    integrity.add(r);
  }
  void gnss(const sim::GnssEpoch& e) {
    health.gnss.record(e.t, f->update(0, gnss_meas(e, s), Vector<2>(e.position.head<2>())));
  }
  void epoch_done(const sim::GnssEpoch& e) {
    (void)f->fuse_and_reset();
    record(track, d, e, L::get<"p">(f->global().mean));
    if (health.lockout(e.t)) {
      auto g = f->global();
      widen(g.cov, s, health.reach(e, L::get<"p">(g.mean)));
      f->reset(g);
    }
  }
};

using OdrMode = imm::Mode<models::PlanarImuModel, imm::Accepts<GnssTag, SpeedTag>, ChiSquareGate>;
using IotrMode = imm::Mode<models::PlanarImuModel, imm::Accepts<GnssTag, UwbTag, SpeedTag>, ChiSquareGate>;
using IdrMode = imm::Mode<models::PlanarImuModel, imm::Accepts<UwbTag, SpeedTag>, ChiSquareGate>;

template <class Mixing>
using RegionImm = imm::Imm<Mixing, OdrMode, IotrMode, IdrMode>;

inline auto make_modes(const Settings& s) {
  const ChiSquareGate gate(s.gate_probability);
  return boost::hana::make_tuple(OdrMode{process_model(s, s.mode_process_noise_factor[0]), gate},
                                 IotrMode{process_model(s, s.mode_process_noise_factor[1]), gate},
                                 IdrMode{process_model(s, s.mode_process_noise_factor[2]), gate});
}

/// Plain IMM (fixed matrix, no routing) or the region-aware one (recognised labels at the
/// GNSS epochs: routing masks and the region-adaptive matrix).
template <class Mixing>
struct ImmSink {
  const sim::Drive& d;
  const Settings& s;
  Mixing mixing;
  const std::vector<int>* labels = nullptr;  // recognised region per GNSS epoch (null: plain IMM)
  const std::vector<Vector<3>>* posteriors = nullptr;  // region posterior per GNSS epoch (PosteriorPull)
  Track track;
  std::optional<RegionImm<Mixing>> f;
  std::array<FilterHealth, 3> health{FilterHealth{s}, FilterHealth{s}, FilterHealth{s}};
  // The IMM as a whole: a source that every mode taking it has gated. Recovering only those
  // modes is not enough when the dominant mode does not take the source, as the next mixing
  // re-centres them on it: leaving a garage whose anchors are all inside (scenario "paper",
  // seed 1), EKF-IDR stayed dominant, ODR and I-OTR gated every fix and the estimate drifted
  // to 135 m. A lock-out of the IMM widens every mode.
  FilterHealth imm_health{s};
  // Integrity of the IMM's output; a fault re-anchors every mode (the next mixing would
  // re-centre a re-anchored mode on the others).
  UwbIntegrity integrity{s};
  std::size_t epoch = 0;
  int region = -1;

  void start(double t0, const Eigen::Vector2d& p0) {
    imm::ImmOptions<3> o;
    o.probability_floor = s.probability_floor;
    f.emplace(mixing, make_modes(s), initial_belief(d, s, t0, p0), Vector<3>::Constant(1.0 / 3.0), o);
    epoch = static_cast<std::size_t>(std::lround(t0 * d.config.gnss.rate_hz));
    set_region();
    f->mix();
  }
  void set_region() {
    if (!labels) return;
    region = epoch < labels->size() ? (*labels)[epoch] : -1;
    f->mixing().observe_region(region);
    if constexpr (requires(Mixing& m) { m.observe_posterior(Vector<3>{}); })
      if (posteriors && epoch < posteriors->size()) f->mixing().observe_posterior((*posteriors)[epoch]);
  }
  std::uint32_t mask(bool gnss) const {
    if (!labels || region < 0 || region == 1) return 0b111u;
    if (region == 0) return gnss ? 0b111u : 0u;  // outdoor: nobody takes UWB
    return gnss ? 0u : 0b111u;                   // indoor: nobody takes GNSS
  }
  /// Calls fn(j) with j = hana::int_c<0>, <1>, <2>: one call per mode.
  template <class Fn>
  static void for_each_mode(Fn&& fn) {
    boost::hana::for_each(boost::hana::make_tuple(boost::hana::int_c<0>, boost::hana::int_c<1>, boost::hana::int_c<2>), fn);
  }
  void predict(const models::PlanarImu& u, double dt) {
    // Checked only after a stamp of ranges: combined() is not free, and this runs at 100 Hz.
    if (!integrity.ranges.empty())
      if (const auto fault = integrity.flush(f->combined())) {
        for_each_mode([&](auto j) { reanchor(f->template mode_belief<j.value>(), *fault, s); });
        for (auto& h : health) h.recovered();
        imm_health.recovered();
      }
    (void)f->predict(u, dt);
  }
  void cycle_start() {}
  void speed(const sim::SpeedSample& v) {
    if (s.use_speed)
      (void)f->update(SpeedTag{}, speed_meas(s), Vector<2>(v.speed_mps, 0.0));
    else if (s.use_nhc)
      (void)f->update(SpeedTag{}, nhc_meas(s), Vector<1>(0.0));
  }
  void uwb(const sim::UwbRange& r) {
    const auto m = boost::hana::make_tuple(uwb_meas(r, s), uwb_meas(r, s, s.iotr_noise_factor), uwb_meas(r, s));
    record_health(r.t, f->update(UwbTag{}, m, Vector<1>(r.range_m), mask(false)), false);
    if (mask(false) != 0u) integrity.add(r);
  }
  // Each mode keeps its own health: a mode that has locked itself out recovers alone.
  void record_health(double t, const imm::UpdateResult<3>& result, bool gnss) {
    const Status* any_accepted = nullptr;
    const Status* any_gated = nullptr;
    for (std::size_t j = 0; j < 3; ++j) {
      if (!result.taken[j]) continue;
      (gnss ? health[j].gnss : health[j].uwb).record(t, result.mode[j]);
      if (result.mode[j].accepted()) any_accepted = &result.mode[j];
      if (result.mode[j].outcome == Outcome::gated) any_gated = &result.mode[j];
    }
    // Accepted by one taker is accepted by the IMM; gated by the IMM only when no taker accepted it.
    if (const Status* st = any_accepted ? any_accepted : any_gated) (gnss ? imm_health.gnss : imm_health.uwb).record(t, *st);
  }
  void gnss(const sim::GnssEpoch& e) {
    const auto m = boost::hana::make_tuple(gnss_meas(e, s), gnss_meas(e, s, s.iotr_noise_factor), gnss_meas(e, s));
    record_health(e.t, f->update(GnssTag{}, m, Vector<2>(e.position.head<2>()), mask(true)), true);
  }
  void epoch_done(const sim::GnssEpoch& e) {
    f->update_mode_probabilities();
    record(track, d, e, L::get<"p">(f->combined().mean), f->most_probable());
    const bool imm_lockout = imm_health.lockout(e.t);
    for_each_mode([&](auto j) {
      auto& h = health[static_cast<std::size_t>(j.value)];
      const bool own = h.lockout(e.t);
      if (!own && !imm_lockout) return;
      if (imm_lockout) h.recovered();  // the mode's counts restart with the IMM's
      auto& b = f->template mode_belief<j.value>();
      const Eigen::Vector2d p = L::get<"p">(b.mean);
      widen(b.cov, s, std::max(own ? h.reach(e, p) : 0.0, imm_lockout ? imm_health.reach(e, p) : 0.0));
    });
    // Next cycle: the region recognised at this epoch (the latest known) routes the
    // measurements until the next epoch.
    epoch = static_cast<std::size_t>(std::lround(e.t * d.config.gnss.rate_hz));
    set_region();
    f->mix();
  }
};

/// Replays the drive through `sink` and returns its track, with the count of integrity
/// re-anchorings for the sinks that have the check.
template <class Sink>
Track track_of(const sim::Drive& d, Sink& sink) {
  replay(d, sink);
  if constexpr (requires { sink.integrity.faults; }) sink.track.integrity_faults = sink.integrity.faults;
  return sink.track;
}

}  // namespace detail

/// Runs one estimator over the drive. `labels` (recognised region per GNSS epoch) is needed
/// by the region IMMs only, `posteriors` (region posterior per GNSS epoch) by
/// Estimator::region_imm_posterior only.
inline Track run(const sim::Drive& d, Estimator e, const Settings& s, const std::vector<int>* labels = nullptr,
                 const std::vector<Vector<3>>* posteriors = nullptr) {
  switch (e) {
    case Estimator::gnss: {
      detail::GnssOnly sink{d, {}};
      return detail::track_of(d, sink);
    }
    case Estimator::uwb: {
      detail::UwbOnly sink{.d = d, .s = s};
      return detail::track_of(d, sink);
    }
    case Estimator::odr:
    case Estimator::iotr:
    case Estimator::idr: {
      const int k = e == Estimator::odr ? 0 : e == Estimator::iotr ? 1 : 2;
      detail::SingleModel sink{d, s, k != 2, k != 0, s.mode_process_noise_factor[static_cast<std::size_t>(k)],
                               k == 1 ? s.iotr_noise_factor : 1.0, {}, {}};
      return detail::track_of(d, sink);
    }
    case Estimator::fkf: {
      detail::Federated sink{d, s, {}, {0.5, 0.5}, {}};
      return detail::track_of(d, sink);
    }
    case Estimator::imm: {
      detail::ImmSink<policies::FixedTransition<3>> sink{
          d, s, policies::FixedTransition<3>(policies::sticky_transition<3>(s.stay_probability)), nullptr, nullptr, {}, {}};
      return detail::track_of(d, sink);
    }
    case Estimator::region_imm: {
      if (!labels) throw std::invalid_argument("region_imm: the region-aware IMM needs the recognised labels");
      detail::ImmSink<policies::RegionAdaptiveTransition<3>> sink{
          d, s,
          policies::RegionAdaptiveTransition<3>(policies::sticky_transition<3>(s.stay_probability), s.prior_weight,
                                                1.0 - s.prior_weight),
          labels, nullptr, {}, {}};
      return detail::track_of(d, sink);
    }
    case Estimator::region_imm_posterior: {
      if (!labels || !posteriors)
        throw std::invalid_argument("region_imm: the posterior-pull IMM needs the recognised labels and posteriors");
      using Pull = policies::PosteriorPull<3, policies::RegionAdaptiveTransition<3>>;
      detail::ImmSink<Pull> sink{
          d, s,
          Pull(policies::RegionAdaptiveTransition<3>(policies::sticky_transition<3>(s.stay_probability), s.prior_weight,
                                                     1.0 - s.prior_weight),
               s.posterior_pull),
          labels, posteriors, {}, {}};
      return detail::track_of(d, sink);
    }
  }
  return {};
}

/// Mean horizontal error per true region and overall; X/Y RMSE per region and overall. `mean`
/// scores every epoch, an estimator without a solution at the position it holds (what its
/// user is left with); `mean_with_solution` scores only the epochs where it has one, and
/// `with_solution` counts them, so that a single sensor's accuracy and its availability are
/// reported apart. Before UWB alone's first acquisition the position it holds is the start
/// fix that every estimator is given, which says nothing about UWB.
struct TrackErrors {
  std::array<double, 4> mean{};    // outdoor, transition, indoor, overall
  std::array<double, 4> rmse_x{};
  std::array<double, 4> rmse_y{};
  std::array<std::size_t, 4> count{};
  std::array<double, 4> mean_with_solution{};  // NaN where there is no such epoch
  std::array<std::size_t, 4> with_solution{};
  double availability(std::size_t k) const {
    return count[k] ? static_cast<double>(with_solution[k]) / static_cast<double>(count[k]) : 0.0;
  }
};

inline TrackErrors errors(const Track& tr) {
  TrackErrors out;
  std::array<double, 4> sum{}, sx{}, sy{}, sum_solution{};
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    const Eigen::Vector2d e = tr.estimate[i] - tr.truth[i];
    const bool solution = i < tr.solution.size() ? tr.solution[i] : true;
    for (int k : {tr.region[i], 3}) {
      const auto kk = static_cast<std::size_t>(k);
      sum[kk] += e.norm();
      sx[kk] += e.x() * e.x();
      sy[kk] += e.y() * e.y();
      ++out.count[kk];
      if (solution) {
        sum_solution[kk] += e.norm();
        ++out.with_solution[kk];
      }
    }
  }
  for (std::size_t k = 0; k < 4; ++k) {
    const double n = std::max<double>(1.0, static_cast<double>(out.count[k]));
    out.mean[k] = sum[k] / n;
    out.rmse_x[k] = std::sqrt(sx[k] / n);
    out.rmse_y[k] = std::sqrt(sy[k] / n);
    out.mean_with_solution[k] = out.with_solution[k] ? sum_solution[k] / static_cast<double>(out.with_solution[k])
                                                     : std::numeric_limits<double>::quiet_NaN();
  }
  return out;
}

}  // namespace ctxfuse::pipelines::region_imm

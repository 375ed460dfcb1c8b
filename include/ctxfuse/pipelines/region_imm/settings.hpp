// Settings of the region paper's pipeline (paper A in docs): one set for every estimator, so
// that the comparison is between methods, not between tunings; and the estimators it runs.
#pragma once

#include <array>
#include <cmath>
#include <vector>

#include "ctxfuse/core/types.hpp"
#include "ctxfuse/models/planar.hpp"
#include "ctxfuse/models/planar_start.hpp"
#include "ctxfuse/policies/health.hpp"
#include "ctxfuse/policies/integrity.hpp"

namespace ctxfuse::pipelines::region_imm {

inline constexpr int kRegions = 3;  // 0 outdoor, 1 transition, 2 indoor

using L = models::PlanarLayout;
using X = Vector<L::size>;

/// The start (alignment from fixes, initial sigmas) is the base's: models/planar_start.hpp.
struct Settings : models::PlanarStartSettings {
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
  // IMM.
  double stay_probability = 0.9;      // fixed prior: diagonal, per 1 s cycle
  double prior_weight = 0.5;          // w_p; w_m = 1 - w_p
  double probability_floor = 1e-4;
  // Extension (not in the paper): region IMM whose matrix is also pulled towards the HMM's
  // causal region posterior, P = (1 - lambda) P_m + lambda 1 pi' (policies::PosteriorPull).
  double posterior_pull = 0.3;
};

// fkf: the federated filter with information-weighted fusion and reset every epoch, which for
// these linearised models equals one centralised filter (the strongest baseline); fkf_static:
// the paper's reading of an FKF, whose master combines the local estimates with fixed weights
// (the information-sharing factors) whatever their covariances.
enum class Estimator { gnss, uwb, odr, iotr, idr, fkf, fkf_static, imm, region_imm, region_imm_posterior };
inline constexpr std::array<Estimator, 10> kAllEstimators{
    Estimator::gnss,       Estimator::uwb, Estimator::odr,        Estimator::iotr,
    Estimator::idr,        Estimator::fkf, Estimator::fkf_static, Estimator::imm,
    Estimator::region_imm, Estimator::region_imm_posterior};
inline const char* name(Estimator e) {
  switch (e) {
    case Estimator::gnss: return "gnss";
    case Estimator::uwb: return "uwb";
    case Estimator::odr: return "odr";
    case Estimator::iotr: return "iotr";
    case Estimator::idr: return "idr";
    case Estimator::fkf: return "fkf";
    case Estimator::fkf_static: return "fkf_static";
    case Estimator::imm: return "imm";
    case Estimator::region_imm: return "region_imm";
    case Estimator::region_imm_posterior: return "region_imm_posterior";
  }
  return "?";
}

/// The recognised region at each receiver epoch (and, for the posterior-pull extension, the
/// HMM's region posterior), looked up by time: the label in force at t is the latest epoch's.
struct RegionTrack {
  std::vector<double> t;
  std::vector<int> label;
  std::vector<Vector<kRegions>> posterior;  // empty, or one per epoch

  /// Index of the latest epoch at or before t; -1 before the first.
  long at(double time) const {
    long k = -1;
    // Epochs arrive in order and the lookups move forward, so a linear walk from the last
    // answer is what a replay costs.
    if (last_ >= 0 && static_cast<std::size_t>(last_) < this->t.size() && this->t[static_cast<std::size_t>(last_)] <= time) k = last_;
    while (static_cast<std::size_t>(k + 1) < this->t.size() && this->t[static_cast<std::size_t>(k + 1)] <= time) ++k;
    last_ = k;
    return k;
  }

 private:
  mutable long last_ = -1;
};

}  // namespace ctxfuse::pipelines::region_imm

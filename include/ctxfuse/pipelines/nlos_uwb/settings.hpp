// Settings of the NLOS-robust UWB pipeline (NLOS paper, section C of the papers digest), one
// set for every recording: nothing here is chosen per case or fitted to a score. Each value
// says where it comes from.
#pragma once

#include <cmath>
#include <string>

#include "ctxfuse/classify/consistency.hpp"
#include "ctxfuse/core/error.hpp"
#include "ctxfuse/policies/health.hpp"

namespace ctxfuse::pipelines::nlos_uwb {

struct Settings {
  // --- UWB ranging -------------------------------------------------------------------------
  // 1-sigma of one DW1000 two-way range. The data sheet gives +-10 cm accuracy, the paper
  // uses 10 cm, and the Hanyang static LOS set (Static_measurements/LOS, 385 files at known
  // distances 2-60 m, 13 heights) agrees: the spread of one file is 2.5 cm (median std) and
  // the per-file mean error varies by 8.6 cm (std over files), sqrt(2.5^2 + 8.6^2) = 9 cm.
  double range_sigma_m = 0.10;
  // Ranges outside (0, max] are refused: a DW1000 link does not close beyond about 300 m
  // (data sheet, 6.8 Mb/s mode, outdoors), so a larger value is a corrupt record.
  double max_range_m = 300.0;

  // --- What a reported range is (the self-calibrating EKF, calibrated_ekf.hpp) ---------------
  // Each anchor's range carries a bias of its own that stays over a run (antenna delay left
  // over from calibration): the static LOS set's per-file mean error varies by 8.6 cm (see
  // range_sigma_m), the data sheet says +-10 cm. The self-calibrating EKF estimates one bias
  // per anchor, a random constant with this prior sigma.
  double anchor_bias_sigma_m = 0.10;
  // The Hanyang system reports, every 100 ms, the mean of an anchor's last 3 raw ranges: on the
  // static start of every dynamic recording the first differences of the ranges have
  // autocorrelation about -0.5 at lag 3 and about 0 at lags 1 and 2, the signature of a
  // 3-sample moving average (differences of white noise give -0.5 at lag 1); printed and checked
  // by tests/pipelines/pipelines_nlos_uwb_real_data_test. Such a report lags the range now by
  // (n - 1) / 2 periods (0.1 s) under constant velocity; the self-calibrating EKF models it as
  // the mean it is (models/averaged_range.hpp). 1: a system that reports each raw range.
  int range_average_samples = 3;
  double range_period_s = 0.1;
  // The fixed-lag output of the self-calibrating EKF: the RTS-smoothed state this far behind
  // the newest range, the fixed-lag smoother's window (10 states at 10 Hz: 0.9 s).
  double smoothed_output_lag_s = 0.9;
  // Records the fixed-lag window holds (one per accepted range, one per epoch's end; allocated
  // once when the estimator is made): 64 covers 0.9 s of up to 6 anchors at 10 Hz; `run uwb`
  // sets it from the recording's anchors and rates (recording.hpp, lag_window_records).
  int lag_records = 64;

  // --- Tag geometry ------------------------------------------------------------------------
  // The tag rides a known height, held (z is not observable tens of metres from anchors spread
  // over a few metres). `run uwb` fits it to the recording's static start (recording.hpp,
  // choose_tag_height) and takes the fit when its vertical sigma is at most
  // tag_height_max_sigma_m: a range moves by at most the height's error (d r / d z = dz / r
  // <= 1), so then by no more than one range's sigma; a VDOP of 1 or less takes anchors nearly
  // overhead (a ceiling). Otherwise, and by default, 1 m: the Hanyang authors' evaluation
  // compares the estimate's z with the reference z + 1 m (data README). On the Hanyang starts
  // (anchors at 0.5 and 1.97 m, 1.9 m x 1.7 m, the tag about 7 m away) the fit says 1.06-1.34 m
  // with a vertical sigma of 0.46-0.47 m: not taken.
  double tag_height_m = 1.0;
  double tag_height_max_sigma_m = 0.10;

  // --- Epochs ------------------------------------------------------------------------------
  // Each anchor ranges at 10 Hz and the four answer within a few ms of each other; an epoch
  // takes one range per anchor within half the 100 ms period of its first range.
  double epoch_window_s = 0.05;

  // --- Motion model (no IMU in the Hanyang recordings) -------------------------------------
  // Constant velocity driven by white acceleration of spectral density q [m^2/s^3]. The
  // platform moves at walking to jogging speed (0.7-0.9 m/s mean) on a track with turns of a
  // few metres radius: v^2 / r about 0.3-1 m/s^2 in turns and similar braking, i.e. an
  // acceleration that changes by ~1 m/s^2 within ~1 s: q = (1 m/s^2)^2 / 1 s.
  double accel_psd = 1.0;
  // The start: position from the first accepted snapshot fix with its covariance; velocity
  // unknown within the platform's top speed (~3 m/s, 1 sigma).
  double initial_speed_sigma_mps = 3.0;
  // Speeds above this are not a wheeled platform at this site: features refuse them.
  double max_speed_mps = 30.0;

  // --- Innovation gate of the EKF ----------------------------------------------------------
  // The textbook 99 % chi-square test (1 dof per range): one in a hundred good ranges lost.
  double gate_probability = 0.99;
  // Lock-out of one anchor: every attached range of it gated for 2 s, at least 5 of them
  // (policies/health.hpp's defaults, PX4 EKF2's practice): the belief, not the anchor, is off.
  policies::SourceHealthOptions lockout{};

  // --- NLOS classifiers (paper eq. 3-8) ----------------------------------------------------
  // Consistency model: the paper's thresholds (1, 2, 3 sigma) and probabilities with the
  // ranging sigma above.
  classify::ConsistencyModel consistency() const {
    classify::ConsistencyModel m;
    m.sigma_uwb = range_sigma_m;
    return m;
  }
  // D-S decision threshold and the mixed-epoch belief of the attach rule (paper: 0.8, 0.7).
  double nlos_belief_threshold = 0.8;
  double mixed_epoch_belief = 0.7;
  // Residual labels for training and scoring the classifiers: a range is NLOS when it exceeds
  // the reference distance by more than 3 range sigmas (issue 16).
  double label_sigma_multiple = 3.0;
  // SVM on (v_u, v_i): RBF, libsvm's C = 1, gamma by cross-validation as in the paper: over
  // libsvm's grid (log2 gamma = 3, 1, ..., -15, standardised units) the best accuracy of
  // svm_cv_folds folds of contiguous time blocks in each class (neighbouring epochs, whose
  // features are alike, stay on one side of a split); ties go to the smaller gamma. false:
  // libsvm's default gamma 1/dim. Training takes every NLOS-labelled row and as many LOS rows
  // (evenly spaced in time), up to svm_rows_per_class per class: balanced classes as in the
  // paper's protocol (half the ranges NLOS), so p1 carries no prior of its own.
  bool svm_gamma_by_cross_validation = true;
  int svm_cv_folds = 5;
  int svm_rows_per_class = 1500;

  SettingCheck check() const {
    auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
    if (!positive(range_sigma_m)) return SettingCheck::refuse("range_sigma_m must be finite and > 0");
    if (!positive(max_range_m)) return SettingCheck::refuse("max_range_m must be finite and > 0");
    if (!std::isfinite(tag_height_m)) return SettingCheck::refuse("tag_height_m must be finite");
    if (!positive(epoch_window_s)) return SettingCheck::refuse("epoch_window_s must be finite and > 0");
    if (!(std::isfinite(anchor_bias_sigma_m) && anchor_bias_sigma_m >= 0.0)) return SettingCheck::refuse("anchor_bias_sigma_m must be finite and >= 0");
    if (range_average_samples < 1 || range_average_samples > 100) return SettingCheck::refuse("range_average_samples must be in 1..100");
    if (!positive(range_period_s)) return SettingCheck::refuse("range_period_s must be finite and > 0");
    if (!(std::isfinite(smoothed_output_lag_s) && smoothed_output_lag_s >= 0.0)) return SettingCheck::refuse("smoothed_output_lag_s must be finite and >= 0");
    if (lag_records < 2 || lag_records > 1'000'000) return SettingCheck::refuse("lag_records must be in 2..1000000");
    if (!positive(accel_psd)) return SettingCheck::refuse("accel_psd must be finite and > 0");
    if (!positive(initial_speed_sigma_mps)) return SettingCheck::refuse("initial_speed_sigma_mps must be finite and > 0");
    if (!positive(max_speed_mps)) return SettingCheck::refuse("max_speed_mps must be finite and > 0");
    if (!(gate_probability > 0.0 && gate_probability < 1.0)) return SettingCheck::refuse("gate_probability must lie in (0, 1)");
    if (!(nlos_belief_threshold > 0.0 && nlos_belief_threshold < 1.0)) return SettingCheck::refuse("nlos_belief_threshold must lie in (0, 1)");
    if (!(mixed_epoch_belief > 0.0 && mixed_epoch_belief < 1.0)) return SettingCheck::refuse("mixed_epoch_belief must lie in (0, 1)");
    if (!positive(label_sigma_multiple)) return SettingCheck::refuse("label_sigma_multiple must be finite and > 0");
    if (!positive(lockout.timeout_s) || lockout.min_rejections < 1) return SettingCheck::refuse("lockout needs timeout_s > 0 and min_rejections >= 1");
    if (svm_rows_per_class < 10) return SettingCheck::refuse("svm_rows_per_class must be >= 10");
    if (svm_cv_folds < 2 || svm_cv_folds > 10) return SettingCheck::refuse("svm_cv_folds must be in 2..10");
    return consistency().check();
  }
};

}  // namespace ctxfuse::pipelines::nlos_uwb

// Multi-sensor consistency model (NLOS paper, eq. 3-6) and the decision rules that follow
// the Dempster-Shafer fusion (eq. 8 and the factor-attach strategy of section 3).
//
// Between two UWB epochs a LOS range can change at most by the distance the vehicle
// travelled (plus ranging noise), so e = |d_rho| - d_d much larger than sigma_uwb points to
// NLOS. The step function mapping e to an NLOS probability has its thresholds (in multiples of
// sigma_uwb) and probabilities as parameters; the defaults are the paper's.
#pragma once

#include <array>
#include <cmath>
#include <string>

#include "ctxfuse/core/error.hpp"

namespace ctxfuse::classify {

struct ConsistencyModel {
  double sigma_uwb = 0.10;                          // UWB ranging std [m] (paper: 10 cm)
  std::array<double, 3> sigma_multiples{1.0, 2.0, 3.0};
  /// NLOS probability for e <= t1, t1 < e <= t2, t2 < e <= t3, e > t3 (t = multiple * sigma).
  std::array<double, 4> probabilities{0.35, 0.55, 0.70, 0.90};

  /// Usable, or which parameter is out of range.
  SettingCheck check() const {
    if (!(sigma_uwb > 0.0) || !std::isfinite(sigma_uwb)) return SettingCheck::refuse("sigma_uwb must be finite and > 0");
    for (int i = 0; i < 3; ++i) {
      if (!std::isfinite(sigma_multiples[i])) return SettingCheck::refuse("sigma_multiples must be finite");
      if (i > 0 && !(sigma_multiples[i] > sigma_multiples[i - 1]))
        return SettingCheck::refuse("sigma_multiples must be strictly increasing");
    }
    for (double p : probabilities)
      if (!(p >= 0.0 && p <= 1.0)) return SettingCheck::refuse("probabilities must lie in [0, 1]");
    return {};
  }

  /// e = |d_rho| - d_d (eq. 3-5): range change minus travelled distance [m].
  static double consistency_error(double range_change, double travelled_distance) {
    return std::abs(range_change) - travelled_distance;
  }

  /// p2 of eq. 6 for a consistency error e; NaN when e is NaN (no evidence).
  double nlos_probability(double e) const {
    if (std::isnan(e)) return e;
    int bin = 0;
    while (bin < 3 && e > sigma_multiples[bin] * sigma_uwb) ++bin;
    return probabilities[bin];
  }

  double nlos_probability(double range_change, double travelled_distance) const {
    return nlos_probability(consistency_error(range_change, travelled_distance));
  }
};

/// Eq. 8 decision: a range is NLOS when the fused NLOS belief R exceeds the threshold.
struct NlosDecisionRule {
  double threshold = 0.8;
  bool is_nlos(double fused_nlos_belief) const { return fused_nlos_belief > threshold; }
  bool operator()(double fused_nlos_belief) const { return is_nlos(fused_nlos_belief); }
};

/// Whether an epoch's UWB factor enters the factor graph. The paper: attach when every range
/// is LOS; also attach when fewer than half of the ranges are NLOS and "the optimal probability
/// R from D-S is above 0.7"; otherwise leave it out. The paper does not say which range's R
/// that is, so this policy takes it as an argument (`belief`) and the caller states its choice.
struct FactorAttachPolicy {
  double mixed_belief_threshold = 0.7;
  bool attach(int total_ranges, int nlos_ranges, double belief) const {
    if (total_ranges <= 0 || nlos_ranges < 0 || nlos_ranges > total_ranges) return false;
    if (nlos_ranges == 0) return true;
    return 2 * nlos_ranges < total_ranges && belief > mixed_belief_threshold;
  }
};

}  // namespace ctxfuse::classify

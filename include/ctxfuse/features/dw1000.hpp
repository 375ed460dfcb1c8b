// DW1000 receive diagnostics as features that carry over between installations. The raw
// register values (first-path amplitudes FP_AMPL1..3, CIR power CIR_PWR, standard deviation of
// the CIR noise STD_NOISE) scale with the preamble accumulation count RXPACC, which depends on
// the preamble length and radio settings; the user manual (DW1000 User Manual, section 4.7
// "Assessing the quality of reception and the RX timestamp") normalises them by RXPACC^2 and
// turns them into dBm:
//   first-path power  FP = 10 log10((F1^2 + F2^2 + F3^2) / N^2) - A
//   received power    RX = 10 log10(C 2^17 / N^2) - A
// with N = RXPACC, C = CIR_PWR and A = 113.77 for a 16 MHz PRF, 121.74 for 64 MHz.
// The noise is put on the same scale as one first-path amplitude (10 log10(STD_NOISE^2 / N^2)
// - A), so that FP minus it is a signal-to-noise ratio of the first path (plus 10 log10 3 for
// the three amplitudes). RX - FP grows when the direct path is blocked (Decawave
// application note APS006 part 3: below 6 dB probably LOS, above 10 dB probably NLOS).
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <string_view>

#include "ctxfuse/core/status.hpp"

namespace ctxfuse::features {

/// The register values of one received frame.
struct Dw1000Diagnostics {
  double range_m = 0.0;
  double fp_amp1 = 0.0, fp_amp2 = 0.0, fp_amp3 = 0.0;  // FP_AMPL1, FP_AMPL2, FP_AMPL3
  double cir_power = 0.0;                               // CIR_PWR
  double rxpacc = 0.0;                                  // preamble accumulation count
  double std_noise = 0.0;                               // STD_NOISE
  double prf_mhz = 64.0;                                // 16 or 64
};

inline constexpr int kDw1000FeatureCount = 5;
inline constexpr std::array<std::string_view, kDw1000FeatureCount> kDw1000FeatureNames{
    "rx_power_dbm", "fp_power_dbm", "rx_minus_fp_db", "noise_dbm", "range_m"};

struct Dw1000Features {
  double rx_power_dbm = 0.0;
  double fp_power_dbm = 0.0;
  double rx_minus_fp_db = 0.0;
  double noise_dbm = 0.0;
  double range_m = 0.0;
  std::array<double, kDw1000FeatureCount> values() const {
    return {rx_power_dbm, fp_power_dbm, rx_minus_fp_db, noise_dbm, range_m};
  }
};

/// The manual's constant A [dB] for a pulse repetition frequency; NaN for any other PRF.
constexpr double dw1000_power_constant(double prf_mhz) {
  return prf_mhz == 16.0 ? 113.77 : prf_mhz == 64.0 ? 121.74 : std::numeric_limits<double>::quiet_NaN();
}

/// First-path power [dBm] from three amplitudes (the manual passes FP_AMPL1, 2, 3).
inline double dw1000_first_path_power_dbm(double f1, double f2, double f3, double rxpacc, double prf_mhz) {
  return 10.0 * std::log10((f1 * f1 + f2 * f2 + f3 * f3) / (rxpacc * rxpacc)) - dw1000_power_constant(prf_mhz);
}

/// Received power [dBm] from CIR_PWR.
inline double dw1000_rx_power_dbm(double cir_power, double rxpacc, double prf_mhz) {
  return 10.0 * std::log10(cir_power * 131072.0 / (rxpacc * rxpacc)) - dw1000_power_constant(prf_mhz);
}

/// The five features of one frame into `out` (accepted). Refused, `out` untouched: a register
/// value NaN or Inf (non_finite_measurement), invalid_prf, invalid_rxpacc, non_positive_power.
inline Status dw1000_features(const Dw1000Diagnostics& d, Dw1000Features& out) {
  for (double v : {d.range_m, d.fp_amp1, d.fp_amp2, d.fp_amp3, d.cir_power, d.rxpacc, d.std_noise, d.prf_mhz})
    if (!std::isfinite(v)) return Status::invalid(Problem::non_finite_measurement);
  if (std::isnan(dw1000_power_constant(d.prf_mhz))) return Status::invalid(Problem::invalid_prf);
  if (!(d.rxpacc > 0.0)) return Status::invalid(Problem::invalid_rxpacc);
  const double fp_sum = d.fp_amp1 * d.fp_amp1 + d.fp_amp2 * d.fp_amp2 + d.fp_amp3 * d.fp_amp3;
  if (!(d.cir_power > 0.0) || !(fp_sum > 0.0) || !(d.std_noise > 0.0)) return Status::invalid(Problem::non_positive_power);
  const double a = dw1000_power_constant(d.prf_mhz), n2 = d.rxpacc * d.rxpacc;
  Dw1000Features f;
  f.rx_power_dbm = dw1000_rx_power_dbm(d.cir_power, d.rxpacc, d.prf_mhz);
  f.fp_power_dbm = dw1000_first_path_power_dbm(d.fp_amp1, d.fp_amp2, d.fp_amp3, d.rxpacc, d.prf_mhz);
  f.rx_minus_fp_db = f.rx_power_dbm - f.fp_power_dbm;
  f.noise_dbm = 10.0 * std::log10(d.std_noise * d.std_noise / n2) - a;
  f.range_m = d.range_m;
  out = f;
  return Status{};
}

}  // namespace ctxfuse::features

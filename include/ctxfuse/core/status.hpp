// Result of a step of a filter, a classifier or a feature extractor: one vocabulary for all. A
// step either commits (accepted: the estimate changed, the prediction or features were written)
// or leaves everything exactly as it was, and says why: gated by the innovation test, invalid
// input (which one), or a numerical failure. Errors are values, never asserts or exits: an
// estimator in a vehicle must keep going.
// Status is [[nodiscard]]: a step that was refused and whose status nobody read is the silent
// failure this type exists to prevent. A caller that may ignore one says why where it does.
#pragma once

#include <cstdint>
#include <limits>
#include <string_view>

namespace ctxfuse {

enum class Outcome : std::uint8_t {
  accepted,           // the estimate was changed (from score(): an update would change it); a
                      // classifier or extractor wrote its output
  gated,              // measurement valid but rejected by the gate; statistic/threshold tell why
  invalid_input,      // a caller-supplied value is unusable; `problem` names it
  numerical_failure,  // the numbers went bad inside the step; `problem` names where
};

enum class Problem : std::uint8_t {
  none,
  non_finite_measurement,
  measurement_magnitude,          // |z| above FilterOptions::max_abs_measurement
  measurement_out_of_domain,      // e.g. a negative range; reported by the model's check()
  measurement_noise_non_finite,
  measurement_noise_not_positive_definite,
  non_finite_input,
  input_magnitude,                // |u| above FilterOptions::max_abs_input (or model's own check)
  process_noise_non_finite,
  process_noise_negative_variance,
  non_finite_dt,
  non_positive_dt,
  dt_above_maximum,
  out_of_order_time,
  time_not_set,
  non_finite_prediction,          // the model produced NaN/Inf (state or Jacobian)
  innovation_not_positive_definite,
  non_finite_covariance,
  non_finite_state,
  non_finite_prior,  // the belief handed to a step holds NaN or Inf (the caller's; invalid input)
  covariance_not_positive_definite,  // a covariance that must be is not: a caller-supplied one
                                     // (e.g. a reset; invalid input) or a filter's own (fusion;
                                     // numerical failure)
  // Snapshot solutions (filters/multilateration.hpp).
  too_few_measurements,      // fewer than the unknowns need
  degenerate_geometry,       // the normal equations are (nearly) singular
  not_converged,             // the iterations did not settle
  residual_above_threshold,  // the fit is inconsistent with the measurement noise (an outlier)
  // Filters made of several filters (filters/imm.hpp, filters/federated.hpp).
  imm_cycle_not_closed,              // mix() again before update_mode_probabilities()
  transition_matrix_not_stochastic,  // the mixing policy's matrix: negative, NaN or a row sum != 1
  mode_probabilities_vanished,       // c_j = sum_i p_ij mu_i not finite or zero for every j
  local_filter_index_out_of_range,   // a federated filter's local filter index
  // Factor-graph smoothers (filters/fixed_lag.hpp).
  system_not_positive_definite,  // the window's normal equations (or the block being
                                 // marginalised) are not positive definite
  measurement_count_above_capacity,  // more measurements in an epoch than its fixed slots
  // Run-time sized arguments (an Eigen::VectorXd, a Map, a dynamic block) at a fixed-size
  // entry point: refused before a single element is read (core/validation.hpp).
  measurement_wrong_size,  // z's rows x cols is not the measurement model's dim x 1
  input_wrong_size,        // u's rows x cols is not the process model's Input
  input_wrong_kind,        // u is another kind than the model takes (IMU increments where rates are expected)
  // Classifiers and feature extractors (classify/, features/): the same Status as the filters.
  non_finite_time,        // a time stamp is NaN or Inf
  input_out_of_domain,    // an input (e.g. a speed or a travelled distance) outside its range
  non_finite_features,    // a classifier's feature vector holds NaN or Inf
  feature_magnitude,      // a feature above 1e150 in magnitude (an RBF kernel would overflow)
  features_wrong_size,    // a run-time sized feature vector whose length is not the model's dimension
  invalid_mass,           // belief masses not finite, negative, or not summing to one
  total_conflict,         // the evidence sources contradict each other completely (K = 0)
  zero_likelihood,        // no hidden state can have produced the observation
  invalid_elevation,      // a satellite elevation infinite or outside [-90, 90] deg
  invalid_azimuth,        // a satellite azimuth infinite
  invalid_cn0,            // a satellite C/N0 outside [0, 100] dB-Hz
  invalid_dop,            // a dilution of precision given but not positive
  duplicate_satellite,    // one satellite id twice in one epoch
  invalid_prf,            // a UWB pulse repetition frequency other than 16 or 64 MHz
  invalid_rxpacc,         // a UWB preamble accumulation count not above zero
  non_positive_power,     // UWB CIR power, first-path amplitudes or noise give no positive power
  // Construction (core/error.hpp): a check function's verdict on a setting.
  invalid_setting,  // a setting outside its range (shares, weights, probabilities, counts)
};

/// The last Problem, for code that walks them all (keep it the last enumerator above).
inline constexpr Problem last_problem = Problem::invalid_setting;

constexpr std::string_view describe(Problem p) {
  switch (p) {
    case Problem::none: return "none";
    case Problem::non_finite_measurement: return "measurement contains NaN or Inf";
    case Problem::measurement_magnitude: return "measurement magnitude above the configured maximum";
    case Problem::measurement_out_of_domain: return "measurement outside the model's domain";
    case Problem::measurement_noise_non_finite: return "measurement noise contains NaN or Inf";
    case Problem::measurement_noise_not_positive_definite: return "measurement noise is not positive definite";
    case Problem::non_finite_input: return "process input contains NaN or Inf";
    case Problem::input_magnitude: return "process input magnitude above the configured maximum";
    case Problem::process_noise_non_finite: return "process noise contains NaN or Inf";
    case Problem::process_noise_negative_variance: return "process noise has a negative variance";
    case Problem::non_finite_dt: return "time step is NaN or Inf";
    case Problem::non_positive_dt: return "time step is zero or negative";
    case Problem::dt_above_maximum: return "time step above the configured maximum";
    case Problem::out_of_order_time: return "time stamp out of order (earlier than the last one, or equal where an interval must be positive)";
    case Problem::time_not_set: return "filter time not set before a timed step";
    case Problem::non_finite_prediction: return "model prediction or Jacobian contains NaN or Inf";
    case Problem::innovation_not_positive_definite: return "innovation covariance is not positive definite";
    case Problem::non_finite_covariance: return "updated covariance contains NaN or Inf";
    case Problem::non_finite_state: return "updated state contains NaN or Inf";
    case Problem::non_finite_prior: return "prior belief contains NaN or Inf";
    case Problem::covariance_not_positive_definite: return "covariance is not positive definite";
    case Problem::imm_cycle_not_closed: return "IMM cycle not closed: mix() called again before update_mode_probabilities()";
    case Problem::transition_matrix_not_stochastic: return "mode transition matrix is not row-stochastic";
    case Problem::mode_probabilities_vanished: return "predicted mode probabilities are not finite or all zero";
    case Problem::local_filter_index_out_of_range: return "local filter index out of range";
    case Problem::system_not_positive_definite: return "normal equations of the window are not positive definite";
    case Problem::measurement_count_above_capacity: return "more measurements than the epoch's fixed slots";
    case Problem::measurement_wrong_size: return "measurement vector has the wrong size for the measurement model";
    case Problem::input_wrong_size: return "process input has the wrong size for the process model";
    case Problem::input_wrong_kind: return "process input is another kind than the process model takes";
    case Problem::non_finite_time: return "time stamp is NaN or Inf";
    case Problem::input_out_of_domain: return "input outside its range (e.g. a negative speed or distance)";
    case Problem::non_finite_features: return "feature vector contains NaN or Inf";
    case Problem::feature_magnitude: return "feature magnitude above 1e150 (the kernel would overflow)";
    case Problem::features_wrong_size: return "feature vector length differs from the model's dimension";
    case Problem::invalid_mass: return "belief masses not finite, negative or not summing to one";
    case Problem::total_conflict: return "evidence sources contradict each other completely";
    case Problem::zero_likelihood: return "no hidden state can have produced the observation";
    case Problem::invalid_elevation: return "satellite elevation infinite or outside [-90, 90] deg";
    case Problem::invalid_azimuth: return "satellite azimuth infinite";
    case Problem::invalid_cn0: return "satellite C/N0 outside [0, 100] dB-Hz";
    case Problem::invalid_dop: return "dilution of precision given but not positive";
    case Problem::duplicate_satellite: return "satellite id listed twice in one epoch";
    case Problem::invalid_prf: return "PRF is neither 16 nor 64 MHz";
    case Problem::invalid_rxpacc: return "preamble accumulation count is not > 0";
    case Problem::non_positive_power: return "CIR power, first-path amplitudes or noise give no positive power";
    case Problem::invalid_setting: return "a setting is outside its range";
    case Problem::too_few_measurements: return "fewer measurements than unknowns";
    case Problem::degenerate_geometry: return "geometry too poor to solve (nearly singular normal equations)";
    case Problem::not_converged: return "the solution did not converge";
    case Problem::residual_above_threshold: return "residuals inconsistent with the measurement noise";
  }
  return "unknown";
}

constexpr std::string_view describe(Outcome o) {
  switch (o) {
    case Outcome::accepted: return "accepted";
    case Outcome::gated: return "gated";
    case Outcome::invalid_input: return "invalid input";
    case Outcome::numerical_failure: return "numerical failure";
  }
  return "unknown";
}

struct [[nodiscard]] Status {
  Outcome outcome = Outcome::accepted;
  Problem problem = Problem::none;
  int dof = 0;  // measurement dimension for updates, 0 for predictions
  // Normalised innovation squared y' S^-1 y, and the gate threshold it was compared with.
  double nis = std::numeric_limits<double>::quiet_NaN();
  double gate_threshold = std::numeric_limits<double>::infinity();
  // log N(y; 0, S): what an IMM needs for mode probabilities. Set for accepted and gated.
  double log_likelihood = std::numeric_limits<double>::quiet_NaN();

  constexpr bool accepted() const { return outcome == Outcome::accepted; }
  constexpr explicit operator bool() const { return accepted(); }

  static constexpr Status invalid(Problem p) { return Status{Outcome::invalid_input, p}; }
  static constexpr Status failure(Problem p) { return Status{Outcome::numerical_failure, p}; }
};

}  // namespace ctxfuse

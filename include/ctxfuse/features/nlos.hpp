// Per-anchor UWB NLOS features (NLOS paper, eq. 1-5 and the dataset's diagnostics):
// range rate v_u = (rho_k - rho_{k-1}) / dt, the vehicle speed v_i, range change d_rho,
// travelled distance d_d, the consistency error e = |d_rho| - d_d, and RSSI minus first-path
// RSSI (grows when the direct path is blocked) where the receiver reports both.
// One extractor per anchor; a step stores one previous sample, so it never allocates.
#pragma once

#include <array>
#include <cmath>
#include <limits>

#include "ctxfuse/core/error.hpp"
#include "ctxfuse/core/status.hpp"

namespace ctxfuse::features {

struct UwbRangeSample {
  double time_s = 0.0;
  double range_m = 0.0;
  double rssi_dbm = std::numeric_limits<double>::quiet_NaN();             // NaN: not reported
  double first_path_rssi_dbm = std::numeric_limits<double>::quiet_NaN();  // NaN: not reported
};

struct NlosFeatures {
  double range_rate_mps = std::numeric_limits<double>::quiet_NaN();  // v_u
  double vehicle_speed_mps = std::numeric_limits<double>::quiet_NaN();  // v_i
  double range_change_m = std::numeric_limits<double>::quiet_NaN();  // d_rho
  double travelled_distance_m = std::numeric_limits<double>::quiet_NaN();  // d_d
  double consistency_error_m = std::numeric_limits<double>::quiet_NaN();  // |d_rho| - d_d
  double rssi_minus_first_path_db = std::numeric_limits<double>::quiet_NaN();
  /// False on an anchor's first sample: the rate-type features (range rate, range change,
  /// travelled distance, consistency error) need a previous range and stay NaN.
  bool has_previous_sample = false;
};

class NlosFeatureExtractor {
 public:
  double max_range_m = 1000.0;
  double max_speed_mps = 100.0;

  void reset() { has_previous_ = false; }

  /// Features of `sample` given the vehicle speed and the distance travelled since the
  /// anchor's previous sample (e.g. integrated odometry/INS speed). Accepted: `out` holds the
  /// features (out.has_previous_sample false on the anchor's first sample). Refused (invalid
  /// input; the extractor keeps its previous sample and `out` is untouched):
  ///   non_finite_time, non_finite_measurement (range), measurement_out_of_domain (negative
  ///   range), measurement_magnitude (range above max_range_m), non_finite_input (speed or
  ///   distance), input_out_of_domain (speed negative or above max_speed_mps, distance
  ///   negative), out_of_order_time (time not after the previous sample's).
  Status push(const UwbRangeSample& sample, double vehicle_speed_mps, double travelled_distance_m,
              NlosFeatures& out) {
    if (!std::isfinite(sample.time_s)) return Status::invalid(Problem::non_finite_time);
    if (!std::isfinite(sample.range_m)) return Status::invalid(Problem::non_finite_measurement);
    if (sample.range_m < 0.0) return Status::invalid(Problem::measurement_out_of_domain);
    if (sample.range_m > max_range_m) return Status::invalid(Problem::measurement_magnitude);
    if (!std::isfinite(vehicle_speed_mps) || !std::isfinite(travelled_distance_m))
      return Status::invalid(Problem::non_finite_input);
    if (!(vehicle_speed_mps >= 0.0 && vehicle_speed_mps <= max_speed_mps) || !(travelled_distance_m >= 0.0))
      return Status::invalid(Problem::input_out_of_domain);
    if (has_previous_ && !(sample.time_s > previous_.time_s)) return Status::invalid(Problem::out_of_order_time);

    NlosFeatures f;
    f.vehicle_speed_mps = vehicle_speed_mps;
    f.rssi_minus_first_path_db = sample.rssi_dbm - sample.first_path_rssi_dbm;
    if (!std::isfinite(f.rssi_minus_first_path_db))
      f.rssi_minus_first_path_db = std::numeric_limits<double>::quiet_NaN();
    if (has_previous_) {
      const double dt = sample.time_s - previous_.time_s;
      f.range_change_m = sample.range_m - previous_.range_m;
      f.range_rate_mps = f.range_change_m / dt;
      f.travelled_distance_m = travelled_distance_m;
      f.consistency_error_m = std::abs(f.range_change_m) - travelled_distance_m;
      f.has_previous_sample = true;
    }
    previous_ = sample;
    has_previous_ = true;
    out = f;
    return {};
  }

  /// Same, with the travelled distance taken as speed * dt (constant speed between samples).
  Status push(const UwbRangeSample& sample, double vehicle_speed_mps, NlosFeatures& out) {
    const double dt = has_previous_ ? sample.time_s - previous_.time_s : 0.0;
    const double distance = (std::isfinite(dt) && dt > 0.0) ? vehicle_speed_mps * dt : 0.0;
    return push(sample, vehicle_speed_mps, std::isfinite(distance) ? distance : 0.0, out);
  }

 private:
  UwbRangeSample previous_{};
  bool has_previous_ = false;
};

}  // namespace ctxfuse::features


namespace ctxfuse::features {

/// Causal window statistics of one anchor link over its last `window` ranges (at most
/// Capacity): mean and std of the range residual (measured minus expected range: the true
/// distance in static tests, the range predicted from the estimated position in a filter),
/// mean RSSI and mean RSSI minus first-path RSSI. A single range is noisy (DW1000 std a few
/// cm) against NLOS biases of a few cm to dm; averaging a short window is what separates them.
template <int Capacity = 64>
class RangeWindowFeatures {
  static_assert(Capacity >= 1);

 public:
  struct Output {
    double residual_mean_m = 0.0;
    double residual_std_m = 0.0;
    double rssi_mean_dbm = 0.0;
    double rssi_minus_first_path_mean_db = 0.0;
    int samples = 0;
  };

  /// Problem::invalid_setting unless 1 <= window <= Capacity (the constructor's check).
  static constexpr Problem check(int window) {
    return window >= 1 && window <= Capacity ? Problem::none : Problem::invalid_setting;
  }
  explicit RangeWindowFeatures(int window = 10) : window_(window) {
    if (check(window) != Problem::none)
      ctxfuse::detail::invalid_setting("RangeWindowFeatures: window must be in [1, Capacity]");
  }

  void reset() { size_ = head_ = 0; }

  /// Adds one range and writes the window's statistics (accepted); a value that is not finite
  /// is refused (Problem::non_finite_measurement) and changes nothing.
  Status push(double residual_m, double rssi_dbm, double first_path_rssi_dbm, Output& out) {
    if (!std::isfinite(residual_m) || !std::isfinite(rssi_dbm) || !std::isfinite(first_path_rssi_dbm))
      return Status::invalid(Problem::non_finite_measurement);
    residual_[head_] = residual_m;
    rssi_[head_] = rssi_dbm;
    diff_[head_] = rssi_dbm - first_path_rssi_dbm;
    head_ = (head_ + 1) % window_;
    size_ = size_ < window_ ? size_ + 1 : window_;
    Output o;
    o.samples = size_;
    for (int i = 0; i < size_; ++i) {
      o.residual_mean_m += residual_[i];
      o.rssi_mean_dbm += rssi_[i];
      o.rssi_minus_first_path_mean_db += diff_[i];
    }
    o.residual_mean_m /= size_;
    o.rssi_mean_dbm /= size_;
    o.rssi_minus_first_path_mean_db /= size_;
    double sq = 0.0;
    for (int i = 0; i < size_; ++i) sq += (residual_[i] - o.residual_mean_m) * (residual_[i] - o.residual_mean_m);
    o.residual_std_m = std::sqrt(sq / size_);
    out = o;
    return {};
  }

  int window() const { return window_; }

 private:
  int window_;
  int size_ = 0;
  int head_ = 0;
  std::array<double, Capacity> residual_{}, rssi_{}, diff_{};
};

}  // namespace ctxfuse::features

// Per-anchor UWB NLOS features (NLOS paper, eq. 1-5 and the dataset's diagnostics):
// range rate v_u = (rho_k - rho_{k-1}) / dt, the vehicle speed v_i, range change d_rho,
// travelled distance d_d, the consistency error e = |d_rho| - d_d, and RSSI minus first-path
// RSSI (grows when the direct path is blocked) where the receiver reports both.
// One extractor per anchor; a step stores one previous sample, so it never allocates.
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string_view>

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
};

enum class NlosFeatureStatus {
  ok,
  first_sample,        // stored; rate-type features need a previous range (they stay NaN)
  non_finite_time,
  non_finite_range,
  negative_range,
  range_too_large,     // above max_range_m
  time_not_increasing,
  invalid_speed,       // NaN/Inf, negative, or above max_speed_mps
  invalid_distance,    // travelled distance NaN/Inf or negative
};

constexpr std::string_view describe(NlosFeatureStatus s) {
  switch (s) {
    case NlosFeatureStatus::ok: return "ok";
    case NlosFeatureStatus::first_sample: return "first sample of the anchor: no range rate yet";
    case NlosFeatureStatus::non_finite_time: return "sample time is NaN or Inf";
    case NlosFeatureStatus::non_finite_range: return "range is NaN or Inf";
    case NlosFeatureStatus::negative_range: return "range is negative";
    case NlosFeatureStatus::range_too_large: return "range above the configured maximum";
    case NlosFeatureStatus::time_not_increasing: return "sample time not after the previous sample";
    case NlosFeatureStatus::invalid_speed: return "vehicle speed NaN/Inf, negative or above the maximum";
    case NlosFeatureStatus::invalid_distance: return "travelled distance NaN/Inf or negative";
  }
  return "unknown";
}

class NlosFeatureExtractor {
 public:
  double max_range_m = 1000.0;
  double max_speed_mps = 100.0;

  void reset() { has_previous_ = false; }

  /// Features of `sample` given the vehicle speed and the distance travelled since the
  /// anchor's previous sample (e.g. integrated odometry/INS speed). On an error status the
  /// extractor keeps its previous sample and `out` is untouched.
  NlosFeatureStatus push(const UwbRangeSample& sample, double vehicle_speed_mps,
                         double travelled_distance_m, NlosFeatures& out) {
    if (!std::isfinite(sample.time_s)) return NlosFeatureStatus::non_finite_time;
    if (!std::isfinite(sample.range_m)) return NlosFeatureStatus::non_finite_range;
    if (sample.range_m < 0.0) return NlosFeatureStatus::negative_range;
    if (sample.range_m > max_range_m) return NlosFeatureStatus::range_too_large;
    if (!(vehicle_speed_mps >= 0.0 && vehicle_speed_mps <= max_speed_mps))
      return NlosFeatureStatus::invalid_speed;
    if (!(travelled_distance_m >= 0.0) || !std::isfinite(travelled_distance_m))
      return NlosFeatureStatus::invalid_distance;
    if (has_previous_ && !(sample.time_s > previous_.time_s)) return NlosFeatureStatus::time_not_increasing;

    NlosFeatures f;
    f.vehicle_speed_mps = vehicle_speed_mps;
    f.rssi_minus_first_path_db = sample.rssi_dbm - sample.first_path_rssi_dbm;
    if (!std::isfinite(f.rssi_minus_first_path_db))
      f.rssi_minus_first_path_db = std::numeric_limits<double>::quiet_NaN();
    NlosFeatureStatus status = NlosFeatureStatus::first_sample;
    if (has_previous_) {
      const double dt = sample.time_s - previous_.time_s;
      f.range_change_m = sample.range_m - previous_.range_m;
      f.range_rate_mps = f.range_change_m / dt;
      f.travelled_distance_m = travelled_distance_m;
      f.consistency_error_m = std::abs(f.range_change_m) - travelled_distance_m;
      status = NlosFeatureStatus::ok;
    }
    previous_ = sample;
    has_previous_ = true;
    out = f;
    return status;
  }

  /// Same, with the travelled distance taken as speed * dt (constant speed between samples).
  NlosFeatureStatus push(const UwbRangeSample& sample, double vehicle_speed_mps, NlosFeatures& out) {
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

  explicit RangeWindowFeatures(int window = 10) : window_(window) {
    if (window < 1 || window > Capacity)
      throw std::invalid_argument("RangeWindowFeatures: window must be in [1, Capacity]");
  }

  void reset() { size_ = head_ = 0; }

  /// Adds one range; returns false (and changes nothing) when a value is not finite.
  bool push(double residual_m, double rssi_dbm, double first_path_rssi_dbm, Output& out) {
    if (!std::isfinite(residual_m) || !std::isfinite(rssi_dbm) || !std::isfinite(first_path_rssi_dbm)) return false;
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
    return true;
  }

  int window() const { return window_; }

 private:
  int window_;
  int size_ = 0;
  int head_ = 0;
  std::array<double, Capacity> residual_{}, rssi_{}, diff_{};
};

}  // namespace ctxfuse::features

// When the INS constraints apply: static detection from the raw IMU (ZUPT and ZIHR while
// static, the non-holonomic constraint while moving), the magnetometer's relative heading
// since a quasi-static-field epoch (dynamic alignment: models/alignment.hpp). Plain
// state machines with fixed storage: nothing allocates per sample.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <optional>

#include "ctxfuse/core/block_state.hpp"
#include "ctxfuse/models/earth.hpp"
#include "ctxfuse/models/ins_nav.hpp"

namespace ctxfuse::models {

/// Static detection from the raw IMU, for any platform and rate. A parked car with its engine
/// running vibrates its IMU by degrees per second (the real drive's static start: 0.7 / 2.6 /
/// 0.06 deg/s std on the three gyro axes at 100 Hz), so a test on the largest raw rate never
/// fires; vibration averages out over a window while turning does not. Static: over the samples
/// of the last window_s seconds the mean angular-rate vector (less a calibrated bias) is below
/// gyro_threshold and the std of the specific-force magnitude below accel_threshold, and -- when
/// the caller has an attitude -- the mean horizontal acceleration in the navigation frame
/// (C f + g) is below accel_threshold too: braking steadily in a straight line leaves the rates
/// and |f| as still as a stop (|f| changes by 0.2 m/s^2 at 2 m/s^2), the levelled acceleration
/// does not. The window is given in seconds and held as the number of samples the IMU's own
/// rate puts in it, so it means the same at 50 or 400 Hz. The defaults are upstream's ZUPT
/// figures (0.5 s, 0.25 deg/s, 0.25 m/s^2); pipelines/gins/static_start.hpp sets calibrated
/// ones from a recording's static start. `entered_static()` is true on the one sample where a
/// static period starts (ZIHR stores the heading then). Fixed storage: nothing allocates.
class StaticDetector {
 public:
  static constexpr int kCapacity = 512;  // samples in a window: 1.28 s at 400 Hz
  /// gyro_threshold on the window's mean rate (less the bias given by calibrate), accel_threshold
  /// on the window's std of |f| (until calibrate) and on its mean horizontal acceleration.
  explicit StaticDetector(double window_s = 0.5, double gyro_threshold = 0.25 * 3.14159265358979323846 / 180.0,
                          double accel_threshold = 0.25)
      : window_s_(window_s),
        gyro_threshold_(gyro_threshold),
        accel_threshold_(accel_threshold),
        horizontal_threshold_(accel_threshold) {}

  /// New thresholds and the rate bias to take off the window's mean rate (from the static
  /// start, static_thresholds_from_rest); the window's samples are kept.
  void calibrate(double gyro_threshold, double accel_threshold, const Eigen::Vector3d& gyro_bias) {
    gyro_threshold_ = gyro_threshold;
    accel_threshold_ = accel_threshold;
    gyro_bias_ = gyro_bias;
  }

  /// One raw sample at time t (rates in any axes) and the horizontal acceleration in the
  /// navigation frame (zero while there is no attitude). Returns whether the window is static
  /// now. The window is window_s seconds of samples: its count, round(window_s x rate), is fixed
  /// from the rate of the samples so far once that many have come, so that a window of jittered
  /// stamps keeps one length. A non-finite sample, or one not after
  /// the previous, is ignored.
  bool push(double t, const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel,
            const Eigen::Vector2d& horizontal = Eigen::Vector2d::Zero()) {
    entered_ = false;
    if (!std::isfinite(t) || !gyro.allFinite() || !accel.allFinite() || !horizontal.allFinite()) return static_;
    if (seen_ > 0 && !(t > last_t_)) return static_;
    if (seen_ == 0) first_t_ = t;
    last_t_ = t;
    ++seen_;
    if (window_ == 0 && seen_ >= 2) {
      // The window's count from the rate so far, fixed once the samples seen fill it.
      const double rate = static_cast<double>(seen_ - 1) / (t - first_t_);
      const double n = std::clamp(std::round(window_s_ * rate), 2.0, static_cast<double>(kCapacity));
      if (static_cast<double>(seen_) >= n) {
        window_ = static_cast<int>(n);
        while (count_ >= window_) drop_oldest();  // the new sample comes in below
      }
    }
    const int capacity = window_ > 0 ? window_ : kCapacity;
    if (count_ == capacity) drop_oldest();
    const std::size_t i = static_cast<std::size_t>((first_ + count_) % kCapacity);
    gyro_[i] = gyro;
    h_[i] = horizontal;
    f_[i] = accel.norm();
    sum_gyro_ += gyro;
    sum_h_ += horizontal;
    sum_f_ += f_[i];
    sum_f2_ += f_[i] * f_[i];
    ++count_;
    bool now = false;
    if (window_ > 0 && count_ == window_) {
      const double n = window_;
      const double var = std::max(0.0, sum_f2_ / n - (sum_f_ / n) * (sum_f_ / n));
      now = (sum_gyro_ / n - gyro_bias_).norm() < gyro_threshold_ && std::sqrt(var) < accel_threshold_ &&
            (sum_h_ / n).norm() < horizontal_threshold_;
    }
    entered_ = now && !static_;
    static_ = now;
    return static_;
  }
  bool is_static() const { return static_; }
  bool entered_static() const { return entered_; }
  /// Samples in the window (0 until the first window has filled).
  int window_samples() const { return window_; }

 private:
  void drop_oldest() {
    const std::size_t i = static_cast<std::size_t>(first_);
    sum_gyro_ -= gyro_[i];
    sum_h_ -= h_[i];
    sum_f_ -= f_[i];
    sum_f2_ -= f_[i] * f_[i];
    first_ = (first_ + 1) % kCapacity;
    --count_;
  }
  double window_s_;
  double gyro_threshold_, accel_threshold_, horizontal_threshold_;
  Eigen::Vector3d gyro_bias_ = Eigen::Vector3d::Zero();
  std::array<Eigen::Vector3d, kCapacity> gyro_{};
  std::array<Eigen::Vector2d, kCapacity> h_{};
  std::array<double, kCapacity> f_{};
  Eigen::Vector3d sum_gyro_ = Eigen::Vector3d::Zero();
  Eigen::Vector2d sum_h_ = Eigen::Vector2d::Zero();
  double sum_f_ = 0.0, sum_f2_ = 0.0;
  double first_t_ = 0.0, last_t_ = 0.0;
  std::size_t seen_ = 0;
  int window_ = 0, first_ = 0, count_ = 0;
  bool static_ = false, entered_ = false;
};

/// Magnetic heading [rad] of a field measured in body axes, levelled with the attitude's roll
/// and pitch (heading of the horizontal field component, clockwise from the body's forward axis
/// negated: the vehicle heading when the field points north, up to the declination and the
/// vehicle's own field, which the relative heading cancels).
inline double magnetic_heading(const Eigen::Matrix3d& C_nb, const Eigen::Vector3d& field_body) {
  // Level frame: the NED frame turned by the heading, so only roll and pitch remain.
  const double psi = heading_of(C_nb);
  const Eigen::Matrix3d C_level = Eigen::AngleAxisd(-psi, Eigen::Vector3d::UnitZ()).toRotationMatrix() * C_nb;
  const Eigen::Vector3d m = C_level * field_body;
  return std::atan2(-m(1), m(0));
}

/// Relative heading from the magnetometer: at a quasi-static-field epoch k0 it stores the
/// filter's heading and the magnetic heading; later, while the field's magnitude and dip stay
/// within tolerance of k0's, z = heading_k0 + (magnetic heading - magnetic heading_k0) for the
/// Heading measurement model.
class MagRelativeHeading {
 public:
  double magnitude_tolerance = 0.05;  // relative change of |B| that ends the reference
  double dip_tolerance = 0.05;        // [rad] change of the dip angle that ends it

  void start(const Eigen::Matrix3d& C_nb, const Eigen::Vector3d& field_body) {
    heading0_ = heading_of(C_nb);
    mag0_ = magnetic_heading(C_nb, field_body);
    norm0_ = field_body.norm();
    dip0_ = dip(C_nb, field_body);
    active_ = norm0_ > 0.0 && std::isfinite(mag0_);
  }
  bool active() const { return active_; }

  /// The heading measurement now, or nothing when the field is disturbed (the reference ends).
  std::optional<double> heading(const Eigen::Matrix3d& C_nb, const Eigen::Vector3d& field_body) {
    if (!active_ || !all_finite(field_body)) return std::nullopt;
    if (std::abs(field_body.norm() / norm0_ - 1.0) > magnitude_tolerance ||
        std::abs(dip(C_nb, field_body) - dip0_) > dip_tolerance) {
      active_ = false;
      return std::nullopt;
    }
    return PlanarAngleRetraction::wrap(heading0_ + PlanarAngleRetraction::wrap(magnetic_heading(C_nb, field_body) - mag0_));
  }

 private:
  static double dip(const Eigen::Matrix3d& C_nb, const Eigen::Vector3d& b) {
    const Eigen::Vector3d n = C_nb * b;
    return std::atan2(n(2), n.head<2>().norm());
  }
  double heading0_ = 0.0, mag0_ = 0.0, norm0_ = 0.0, dip0_ = 0.0;
  bool active_ = false;
};

}  // namespace ctxfuse::models

// When the INS constraints apply: static detection from the raw IMU (ZUPT and ZIHR while
// static, the non-holonomic constraint while moving), the magnetometer's relative heading
// since a quasi-static-field epoch (dynamic alignment: models/alignment.hpp). Plain
// state machines with fixed storage: nothing allocates per sample.
#pragma once

#include <array>
#include <cmath>
#include <optional>

#include "ctxfuse/core/block_state.hpp"
#include "ctxfuse/models/earth.hpp"
#include "ctxfuse/models/ins_nav.hpp"

namespace ctxfuse::models {

struct StaticDetectorOptions {
  int window = 50;                 // samples (upstream ZUPT window for the drive: 50 epochs)
  double accel_threshold = 0.25;   // [m/s^2] largest |f| - mean |f| over the window
  double gyro_threshold = 0.00436; // [rad/s] (0.25 deg/s) largest |w| over the window
};

/// Static when, over the last `window` raw samples, the specific-force magnitude stays within
/// accel_threshold of its window mean and the angular rate magnitude below gyro_threshold.
/// `entered_static()` is true on the one sample where a static period starts (ZIHR stores
/// the heading then).
class StaticDetector {
 public:
  static constexpr int kCapacity = 512;
  StaticDetector() = default;
  explicit StaticDetector(StaticDetectorOptions o) : options_(o) {
    if (options_.window < 2) options_.window = 2;
    if (options_.window > kCapacity) options_.window = kCapacity;
  }

  /// One raw sample (rates, any axes: only magnitudes are used). Non-finite samples are ignored.
  bool push(const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel) {
    entered_ = false;
    if (!all_finite(gyro) || !all_finite(accel)) return static_;
    accel_norm_[next_] = accel.norm();
    gyro_norm_[next_] = gyro.norm();
    next_ = (next_ + 1) % options_.window;
    if (count_ < options_.window) ++count_;
    bool now = false;
    if (count_ == options_.window) {
      double mean = 0.0, max_gyro = 0.0;
      for (int i = 0; i < count_; ++i) {
        mean += accel_norm_[i];
        max_gyro = std::max(max_gyro, gyro_norm_[i]);
      }
      mean /= count_;
      double max_dev = 0.0;
      for (int i = 0; i < count_; ++i) max_dev = std::max(max_dev, std::abs(accel_norm_[i] - mean));
      now = max_dev < options_.accel_threshold && max_gyro < options_.gyro_threshold;
    }
    entered_ = now && !static_;
    static_ = now;
    return static_;
  }
  bool is_static() const { return static_; }
  bool entered_static() const { return entered_; }
  const StaticDetectorOptions& options() const { return options_; }

 private:
  StaticDetectorOptions options_{};
  std::array<double, kCapacity> accel_norm_{};
  std::array<double, kCapacity> gyro_norm_{};
  int next_ = 0;
  int count_ = 0;
  bool static_ = false;
  bool entered_ = false;
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

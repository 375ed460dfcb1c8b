// Static detection for a vehicle whose engine shakes the IMU, and the statistics of the
// static start. A parked car with its engine running vibrates its IMU by degrees per second
// (the drive's static start: 0.7 / 2.6 / 0.06 deg/s std on the three gyro axes at 100 Hz), so a
// detector on the largest raw rate (models::StaticDetector) never fires; vibration averages out
// over a window while turning does not. Static here: over the last `window` samples the mean
// angular-rate vector is below gyro_threshold and the std of the specific-force magnitude
// below accel_threshold, and -- once the filter has an attitude -- the mean horizontal
// acceleration in the navigation frame (C f + g) is below accel_threshold too: braking
// steadily in a straight line leaves the rates and |f| as still as a stop (|f| changes by
// 0.2 m/s^2 at 2 m/s^2), the levelled acceleration does not. Fixed storage, nothing
// allocates per sample.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstddef>

namespace ctxfuse::pipelines::gins {

class VibrationStaticDetector {
 public:
  static constexpr int kCapacity = 512;
  VibrationStaticDetector(int window, double gyro_threshold, double accel_threshold)
      : window_(window < 2 ? 2 : window > kCapacity ? kCapacity : window), gyro_threshold_(gyro_threshold),
        accel_threshold_(accel_threshold) {}

  /// One raw sample (rates in any axes) and the horizontal acceleration in the navigation
  /// frame (zero while there is no attitude). Returns whether the window is static now.
  bool push(const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel,
            const Eigen::Vector2d& horizontal = Eigen::Vector2d::Zero()) {
    entered_ = false;
    if (!gyro.allFinite() || !accel.allFinite() || !horizontal.allFinite()) return static_;
    const std::size_t i = static_cast<std::size_t>(next_);
    if (count_ == window_) {
      sum_gyro_ -= gyro_[i];
      sum_h_ -= h_[i];
      sum_f_ -= f_[i];
      sum_f2_ -= f_[i] * f_[i];
    }
    gyro_[i] = gyro;
    h_[i] = horizontal;
    f_[i] = accel.norm();
    sum_gyro_ += gyro;
    sum_h_ += horizontal;
    sum_f_ += f_[i];
    sum_f2_ += f_[i] * f_[i];
    next_ = (next_ + 1) % window_;
    if (count_ < window_) ++count_;
    bool now = false;
    if (count_ == window_) {
      const double n = window_;
      const double var = std::max(0.0, sum_f2_ / n - (sum_f_ / n) * (sum_f_ / n));
      now = (sum_gyro_ / n).norm() < gyro_threshold_ && std::sqrt(var) < accel_threshold_ &&
            (sum_h_ / n).norm() < accel_threshold_;
    }
    entered_ = now && !static_;
    static_ = now;
    return static_;
  }
  bool is_static() const { return static_; }
  bool entered_static() const { return entered_; }

 private:
  int window_;
  double gyro_threshold_, accel_threshold_;
  std::array<Eigen::Vector3d, kCapacity> gyro_{};
  std::array<Eigen::Vector2d, kCapacity> h_{};
  std::array<double, kCapacity> f_{};
  Eigen::Vector3d sum_gyro_ = Eigen::Vector3d::Zero();
  Eigen::Vector2d sum_h_ = Eigen::Vector2d::Zero();
  double sum_f_ = 0.0, sum_f2_ = 0.0;
  int next_ = 0, count_ = 0;
  bool static_ = false, entered_ = false;
};

/// Mean and standard deviation of the body-frame rates and specific force over one static run.
struct StaticStats {
  std::size_t samples = 0;
  double duration_s = 0.0;  // first to last static sample (the run may have moving gaps)
  Eigen::Vector3d gyro_mean = Eigen::Vector3d::Zero(), gyro_std = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_mean = Eigen::Vector3d::Zero(), accel_std = Eigen::Vector3d::Zero();
};

class StaticAccumulator {
 public:
  void add(double t, const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel) {
    if (n_ == 0) t0_ = t;
    t1_ = t;
    ++n_;
    sg_ += gyro;
    sgg_ += gyro.cwiseAbs2();
    sa_ += accel;
    saa_ += accel.cwiseAbs2();
  }
  void clear() { *this = StaticAccumulator{}; }
  std::size_t samples() const { return n_; }
  StaticStats stats() const {
    StaticStats s;
    s.samples = n_;
    if (n_ == 0) return s;
    const double n = static_cast<double>(n_);
    s.duration_s = t1_ - t0_;
    s.gyro_mean = sg_ / n;
    s.accel_mean = sa_ / n;
    s.gyro_std = (sgg_ / n - s.gyro_mean.cwiseAbs2()).cwiseMax(0.0).cwiseSqrt();
    s.accel_std = (saa_ / n - s.accel_mean.cwiseAbs2()).cwiseMax(0.0).cwiseSqrt();
    return s;
  }

 private:
  std::size_t n_ = 0;
  double t0_ = 0.0, t1_ = 0.0;
  Eigen::Vector3d sg_ = Eigen::Vector3d::Zero(), sgg_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d sa_ = Eigen::Vector3d::Zero(), saa_ = Eigen::Vector3d::Zero();
};

}  // namespace ctxfuse::pipelines::gins

// Static detection for a vehicle whose engine shakes the IMU, and the statistics of the
// static start. A parked car with its engine running vibrates its IMU by degrees per second
// (the drive's static start: 0.7 / 2.6 / 0.06 deg/s std on the three gyro axes at 100 Hz), so a
// detector on the largest raw rate (models::StaticDetector) never fires; vibration averages out
// over a window while turning does not. Static here: over the samples of the last window_s
// seconds the mean angular-rate vector is below gyro_threshold and the std of the
// specific-force magnitude below accel_threshold, and -- once the filter has an attitude --
// the mean horizontal acceleration in the navigation frame (C f + g) is below
// accel_threshold too: braking steadily in a straight line leaves the rates and |f| as still
// as a stop (|f| changes by 0.2 m/s^2 at 2 m/s^2), the levelled acceleration does not. The
// window is given in seconds and held as the number of samples the IMU's own rate puts in it,
// so it means the same at 50 or 400 Hz. Fixed storage, nothing allocates per sample.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

namespace ctxfuse::pipelines::gins {

class VibrationStaticDetector {
 public:
  static constexpr int kCapacity = 512;  // samples in a window: 1.28 s at 400 Hz
  VibrationStaticDetector(double window_s, double gyro_threshold, double accel_threshold)
      : window_s_(window_s), gyro_threshold_(gyro_threshold), accel_threshold_(accel_threshold) {}

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
      now = (sum_gyro_ / n).norm() < gyro_threshold_ && std::sqrt(var) < accel_threshold_ &&
            (sum_h_ / n).norm() < accel_threshold_;
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
  double gyro_threshold_, accel_threshold_;
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

/// Whether a still IMU may be taken for rest. An IMU cannot tell steady straight motion from
/// rest (a smooth robot at 0.3 m/s reads as still): static also needs the filter's horizontal
/// speed, and the latest used GNSS velocity if it is under `gnss_hold_s` old, below
/// `max_speed` (pipelines/gins/settings.hpp, static_max_speed_mps).
class SpeedEvidence {
 public:
  SpeedEvidence(double max_speed, double gnss_hold_s) : max_speed_(max_speed), hold_s_(gnss_hold_s) {}
  /// A used GNSS velocity (horizontal) at time t.
  void gnss_velocity(double t, const Eigen::Vector2d& v) {
    gnss_t_ = t;
    gnss_moving_ = v.norm() > max_speed_;
  }
  bool allow_static(double t, double filter_speed) const {
    const bool gnss_says_moving = gnss_moving_ && t - gnss_t_ < hold_s_;
    return !gnss_says_moving && filter_speed <= max_speed_;
  }

 private:
  double max_speed_, hold_s_;
  double gnss_t_ = -std::numeric_limits<double>::infinity();
  bool gnss_moving_ = false;
};

/// Allan deviation of a 3-axis stream at one cluster time tau, from non-overlapping clusters
/// (IEEE Std 952-1997, annex C): sigma^2(tau) = 1/2 <(mean_{k+1} - mean_k)^2> over successive
/// clusters of tau seconds, by the samples' own time stamps. For white noise of density N
/// (units/sqrt(Hz)) sigma(tau) = N / sqrt(tau), so sigma at tau = 1 s reads N; vibration at tens
/// of Hz averages out within a cluster and adds next to nothing, while it dominates the
/// per-sample standard deviation. A sample more than tau after the previous one (the run was
/// interrupted) ends the chain: no difference spans a gap. Constant memory.
class AllanAccumulator {
 public:
  explicit AllanAccumulator(double tau_s = 1.0) : tau_(tau_s) {}

  void add(double t, const Eigen::Vector3d& x) {
    if (!std::isfinite(t) || !x.allFinite()) return;
    if (n_ > 0 && (t < last_t_ || t - last_t_ > tau_)) {  // a gap (or time back): a new chain
      have_previous_ = false;
      n_ = 0;
    }
    if (n_ == 0) {
      start_ = t;
    } else if (t >= start_ + tau_) {
      close_cluster();
      start_ += tau_;
    }
    sum_ += x;
    ++n_;
    last_t_ = t;
  }
  /// Per-axis Allan deviation at tau; zero until two successive clusters closed.
  Eigen::Vector3d deviation() const {
    if (differences_ == 0) return Eigen::Vector3d::Zero();
    return (squares_ / (2.0 * static_cast<double>(differences_))).cwiseSqrt();
  }
  std::size_t differences() const { return differences_; }
  double tau() const { return tau_; }

 private:
  void close_cluster() {
    const Eigen::Vector3d mean = sum_ / static_cast<double>(n_);
    if (have_previous_) {
      squares_ += (mean - previous_).cwiseAbs2();
      ++differences_;
    }
    previous_ = mean;
    have_previous_ = true;
    sum_.setZero();
    n_ = 0;
  }
  double tau_;
  double start_ = 0.0, last_t_ = 0.0;
  Eigen::Vector3d sum_ = Eigen::Vector3d::Zero(), previous_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d squares_ = Eigen::Vector3d::Zero();
  std::size_t n_ = 0, differences_ = 0;
  bool have_previous_ = false;
};

/// Mean, standard deviation and Allan deviation at 1 s of the body-frame rates and specific
/// force over one static run.
struct StaticStats {
  std::size_t samples = 0;
  double duration_s = 0.0;  // first to last static sample (the run may have moving gaps)
  Eigen::Vector3d gyro_mean = Eigen::Vector3d::Zero(), gyro_std = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_mean = Eigen::Vector3d::Zero(), accel_std = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_allan_1s = Eigen::Vector3d::Zero(), accel_allan_1s = Eigen::Vector3d::Zero();
  std::size_t allan_differences = 0;  // cluster pairs behind the Allan deviations
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
    allan_gyro_.add(t, gyro);
    allan_accel_.add(t, accel);
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
    s.gyro_allan_1s = allan_gyro_.deviation();
    s.accel_allan_1s = allan_accel_.deviation();
    s.allan_differences = allan_gyro_.differences();
    return s;
  }

 private:
  std::size_t n_ = 0;
  double t0_ = 0.0, t1_ = 0.0;
  Eigen::Vector3d sg_ = Eigen::Vector3d::Zero(), sgg_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d sa_ = Eigen::Vector3d::Zero(), saa_ = Eigen::Vector3d::Zero();
  AllanAccumulator allan_gyro_{1.0}, allan_accel_{1.0};
};

}  // namespace ctxfuse::pipelines::gins

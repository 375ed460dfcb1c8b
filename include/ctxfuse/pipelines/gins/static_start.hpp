// The statistics of the static start and what they decide: the static test's thresholds
// (static_thresholds_from_rest) for the raw-IMU detector (models::StaticDetector,
// models/ins_motion.hpp), and whether a still IMU may be taken for rest (SpeedEvidence).
//
// The thresholds come from the recording's own static start: the detector starts on fallback
// figures (upstream's ZUPT thresholds) that find the start, and the start's statistics then set
// what a window at rest may show on this IMU on this platform (an idling engine, a hand's
// tremor, a rigid robot): the spread of the window-mean rate about the start's mean (its Allan
// deviation at the window's length) and of the window std of |f|.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>

#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/models/ins_motion.hpp"

namespace ctxfuse::pipelines::gins {

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
  // At the static detector's window length: the Allan deviation of the rates (the spread of a
  // window's mean rate about the start's mean) and the mean and std over the start's
  // non-overlapping windows of the within-window std of |f|.
  double window_s = 0.0;
  Eigen::Vector3d gyro_allan_window = Eigen::Vector3d::Zero();
  std::size_t window_differences = 0;
  double f_window_std_mean = 0.0, f_window_std_std = 0.0;
  std::size_t f_windows = 0;
};

/// Mean and std, over non-overlapping clusters of tau seconds (by the samples' stamps), of a
/// scalar's within-cluster standard deviation. A gap longer than tau drops the open cluster.
class ClusterStdAccumulator {
 public:
  explicit ClusterStdAccumulator(double tau_s) : tau_(tau_s) {}
  void add(double t, double x) {
    if (!std::isfinite(t) || !std::isfinite(x)) return;
    if (n_ > 0 && (t < last_t_ || t - last_t_ > tau_)) n_ = 0;
    if (n_ == 0) {
      start_ = t;
    } else if (t >= start_ + tau_) {
      close_cluster();
      start_ += tau_;
      if (t >= start_ + tau_) start_ = t;
    }
    if (n_ == 0) sum_ = sum2_ = 0.0;
    sum_ += x;
    sum2_ += x * x;
    ++n_;
    last_t_ = t;
  }
  std::size_t clusters() const { return m_; }
  double mean() const { return m_ > 0 ? s_ / static_cast<double>(m_) : 0.0; }
  double std() const {
    if (m_ < 2) return 0.0;
    const double m = static_cast<double>(m_), mu = s_ / m;
    return std::sqrt(std::max(0.0, (s2_ - m * mu * mu) / (m - 1.0)));
  }

 private:
  void close_cluster() {
    if (n_ >= 2) {
      const double n = static_cast<double>(n_), mu = sum_ / n;
      const double sd = std::sqrt(std::max(0.0, sum2_ / n - mu * mu));
      s_ += sd;
      s2_ += sd * sd;
      ++m_;
    }
    n_ = 0;
  }
  double tau_;
  double start_ = 0.0, last_t_ = 0.0, sum_ = 0.0, sum2_ = 0.0, s_ = 0.0, s2_ = 0.0;
  std::size_t n_ = 0, m_ = 0;
};

class StaticAccumulator {
 public:
  /// window_s: the static detector's window (StaticStats' window figures).
  explicit StaticAccumulator(double window_s = 0.5)
      : window_s_(window_s), allan_gyro_window_(window_s), f_windows_(window_s) {}
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
    allan_gyro_window_.add(t, gyro);
    f_windows_.add(t, accel.norm());
  }
  void clear() { *this = StaticAccumulator{window_s_}; }
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
    s.window_s = window_s_;
    s.gyro_allan_window = allan_gyro_window_.deviation();
    s.window_differences = allan_gyro_window_.differences();
    s.f_window_std_mean = f_windows_.mean();
    s.f_window_std_std = f_windows_.std();
    s.f_windows = f_windows_.clusters();
    return s;
  }

 private:
  std::size_t n_ = 0;
  double t0_ = 0.0, t1_ = 0.0;
  Eigen::Vector3d sg_ = Eigen::Vector3d::Zero(), sgg_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d sa_ = Eigen::Vector3d::Zero(), saa_ = Eigen::Vector3d::Zero();
  double window_s_;
  AllanAccumulator allan_gyro_{1.0}, allan_accel_{1.0}, allan_gyro_window_;
  ClusterStdAccumulator f_windows_;
};

/// The static test's thresholds and where they came from.
struct StaticThresholds {
  double gyro = 0.0;   // on |window mean rate - gyro_bias| [rad/s]
  double accel = 0.0;  // on a window's std of |f| [m/s^2]
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  bool from_start = false;  // from the recording's static start (else the fallback figures)
};

/// Thresholds that a window at rest on this IMU fails with probability false_alarm each, from
/// the static start's statistics (StaticStats), or nothing when the start is shorter than
/// min_duration_s or holds fewer than 4 windows:
///  - rate: the window's mean rate less the start's mean is, at rest, a 3-vector whose per-axis
///    spread is the Allan deviation at the window's length (IEEE Std 952: half the mean square
///    of successive cluster means' differences), here the largest axis', raised to its one-sided
///    95 % upper confidence bound from the m differences behind it (sigma x sqrt(m /
///    chi2_0.05(m))); threshold sqrt(chi2_{1-false_alarm}(3)) times that;
///  - |f|: the start's windows' std of |f|, mean + z_{1-false_alarm} x std over those windows
///    (vibration included as this IMU on this platform shows it).
/// Each is floored by what white noise of the data sheet's densities gives by the same rule
/// (gyro_floor_density [rad/s/sqrt(Hz)] over the window; accel_floor_density [m/s^2/sqrt(Hz)]
/// at the sampling rate, window_samples / window_s), so a start quieter than the part itself
/// (quantised, or simulated without noise) does not set a threshold that rest never passes.
inline std::optional<StaticThresholds> static_thresholds_from_rest(const StaticStats& s, int window_samples,
                                                                   double min_duration_s, double false_alarm,
                                                                   double gyro_floor_density,
                                                                   double accel_floor_density) {
  if (!(s.duration_s >= min_duration_s) || s.window_differences < 3 || s.f_windows < 4 || window_samples < 2 ||
      !(s.window_s > 0.0) || !(false_alarm > 0.0 && false_alarm < 0.5))
    return std::nullopt;
  const double m = static_cast<double>(s.window_differences);
  const double upper = std::sqrt(m / chi_square_quantile(0.05, static_cast<int>(s.window_differences)));
  const double k3 = std::sqrt(chi_square_quantile(1.0 - false_alarm, 3));
  const double z = std::sqrt(chi_square_quantile(1.0 - 2.0 * false_alarm, 1));  // one-sided normal quantile
  const double rate = static_cast<double>(window_samples) / s.window_s;
  const double nu = static_cast<double>(window_samples - 1);
  StaticThresholds out;
  out.from_start = true;
  out.gyro_bias = s.gyro_mean;
  out.gyro = k3 * std::max(upper * s.gyro_allan_window.maxCoeff(), gyro_floor_density / std::sqrt(s.window_s));
  const double white_f = accel_floor_density * std::sqrt(0.5 * rate);  // a sample's std at this rate
  out.accel = std::max(s.f_window_std_mean + z * s.f_window_std_std,
                       white_f * std::sqrt(chi_square_quantile(1.0 - false_alarm, window_samples - 1) / nu));
  if (!std::isfinite(out.gyro) || !std::isfinite(out.accel)) return std::nullopt;
  return out;
}

}  // namespace ctxfuse::pipelines::gins

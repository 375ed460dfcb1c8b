// How the region pipeline's filters start without truth: dynamic alignment from position
// fixes. A planar IMU filter needs position, velocity and heading; a vehicle that moves
// forward (no side slip) gives the heading as the direction between two fixes, once they are
// far enough apart that the fixes' noise cannot turn it much. The fixes are GNSS fixes or, where
// no GNSS reaches (a drive that starts in a garage), UWB snapshot multilaterations.
//
// The initial covariance comes from the fixes themselves (position: the last fix; velocity:
// the difference of two fixes over their time apart; heading: the difference's cross-track
// spread over its length), each floored by Settings::init_*_sigma, since the vehicle may have
// turned or changed speed between the two fixes. What the fixes cannot see (sensor biases)
// starts at zero with Settings::init_*_bias_sigma.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <numbers>
#include <optional>

#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/pipelines/region_imm/settings.hpp"

namespace ctxfuse::pipelines::region_imm {

/// Position, velocity and heading at time t, with their covariances.
struct Alignment {
  double t = 0.0;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  Eigen::Matrix2d position_cov = Eigen::Matrix2d::Identity();
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();
  Eigen::Matrix2d velocity_cov = Eigen::Matrix2d::Identity();
  double heading = 0.0;  // rad, ENU yaw (counter-clockwise from east)
  double heading_var = 1.0;
};

/// Motion known from elsewhere at the first fix (a static alignment with a magnetometer, the
/// end of a previous drive): the filters then start at the first fix with it.
struct KnownMotion {
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();
  double heading = 0.0;
};

/// Offered fixes in time order, finds the first moment at which a heading can be trusted: the
/// longest baseline within the span (the oldest fix in it more than min_distance away) whose
/// heading 1-sigma, from the two fixes' covariances, is below the maximum.
class DynamicAligner {
 public:
  explicit DynamicAligner(const Settings& s) : s_(s) {}

  /// Forgets every fix offered (a restart aligns afresh).
  void reset() { first_ = count_ = 0; }
  const Settings& settings() const { return s_; }

  /// Offers one fix; returns the alignment at its time when it completes a pair. Non-finite
  /// fixes and fixes not after the previous one are ignored.
  std::optional<Alignment> add(double t, const Eigen::Vector2d& p, const Eigen::Matrix2d& cov) {
    if (!std::isfinite(t) || !p.allFinite() || !cov.allFinite()) return std::nullopt;
    if (count_ > 0 && !(t > at(count_ - 1).t)) return std::nullopt;
    push(Fix{t, p, cov});
    const Fix& now = at(count_ - 1);
    const double max_heading_var = std::pow(s_.align_max_heading_sigma_deg * std::numbers::pi / 180.0, 2);
    for (std::size_t k = 0; k + 1 < count_; ++k) {
      const Fix& a = at(k);
      const Eigen::Vector2d d = now.p - a.p;
      const double len = d.norm();
      if (len <= s_.align_min_distance_m) continue;
      const Eigen::Vector2d across(-d.y() / len, d.x() / len);
      const double heading_var = across.dot((a.cov + now.cov) * across) / (len * len);
      if (heading_var > max_heading_var) continue;
      return align(a, now, d, heading_var);
    }
    return std::nullopt;
  }

 private:
  struct Fix {
    double t;
    Eigen::Vector2d p;
    Eigen::Matrix2d cov;
  };
  Alignment align(const Fix& a, const Fix& b, const Eigen::Vector2d& d, double heading_var) const {
    // Velocity over the latest baseline of at least align_velocity_baseline_s (the long
    // baseline's mean velocity lags while the vehicle accelerates).
    const Fix* v0 = &a;
    for (std::size_t k = count_ - 1; k-- > 0;)
      if (b.t - at(k).t >= s_.align_velocity_baseline_s) {
        v0 = &at(k);
        break;
      }
    const double dt = b.t - v0->t;
    const double v_floor = s_.init_velocity_sigma * s_.init_velocity_sigma;
    const double h_floor = std::pow(s_.init_heading_sigma_deg * std::numbers::pi / 180.0, 2);
    const double p_floor = s_.init_position_sigma * s_.init_position_sigma;
    Alignment al;
    al.t = b.t;
    al.position = b.p;
    al.position_cov = b.cov;
    al.velocity = (b.p - v0->p) / dt;
    al.velocity_cov = (b.cov + v0->cov) / (dt * dt);
    for (int i = 0; i < 2; ++i) {
      al.position_cov(i, i) = std::max(al.position_cov(i, i), p_floor);
      al.velocity_cov(i, i) = std::max(al.velocity_cov(i, i), v_floor);
    }
    al.heading = std::atan2(d.y(), d.x());
    al.heading_var = std::max(heading_var, h_floor);
    return al;
  }
  // The fixes of the last max_span_s, oldest first, in a ring of fixed capacity (fixes faster
  // than kCapacity per span are thinned to the newest).
  static constexpr std::size_t kCapacity = 128;
  const Fix& at(std::size_t k) const { return ring_[(first_ + k) % kCapacity]; }
  void push(const Fix& f) {
    while (count_ > 0 && f.t - at(0).t > s_.align_max_span_s) drop_oldest();
    if (count_ == kCapacity) drop_oldest();
    ring_[(first_ + count_) % kCapacity] = f;
    ++count_;
  }
  void drop_oldest() {
    first_ = (first_ + 1) % kCapacity;
    --count_;
  }
  Settings s_;  // a copy: an aligner may outlive (or be copied away from) the settings it was made from
  std::array<Fix, kCapacity> ring_{};
  std::size_t first_ = 0, count_ = 0;
};

/// The planar filters' initial belief from an alignment.
inline Gaussian<L::size> initial_belief(const Alignment& a, const Settings& s) {
  Gaussian<L::size> b;
  b.mean.setZero();
  L::get<"p">(b.mean) = a.position;
  L::get<"v">(b.mean) = a.velocity;
  L::get<"psi">(b.mean)(0) = a.heading;
  b.cov.setZero();
  L::cov<"p">(b.cov) = a.position_cov;
  L::cov<"v">(b.cov) = a.velocity_cov;
  L::cov<"psi">(b.cov)(0, 0) = a.heading_var;
  L::cov<"bg">(b.cov)(0, 0) = s.init_gyro_bias_sigma * s.init_gyro_bias_sigma;
  L::cov<"ba">(b.cov).diagonal().setConstant(s.init_accel_bias_sigma * s.init_accel_bias_sigma);
  return b;
}

/// The initial belief at a first fix `p0` with known motion: position, velocity and heading
/// with the fixed initial sigmas of Settings.
inline Gaussian<L::size> initial_belief(const Eigen::Vector2d& p0, const KnownMotion& m, const Settings& s) {
  Gaussian<L::size> b;
  b.mean.setZero();
  L::get<"p">(b.mean) = p0;
  L::get<"v">(b.mean) = m.velocity;
  L::get<"psi">(b.mean)(0) = m.heading;
  Vector<L::size> sd;
  const double h = s.init_heading_sigma_deg * std::numbers::pi / 180.0;
  sd << s.init_position_sigma, s.init_position_sigma, s.init_velocity_sigma, s.init_velocity_sigma, h,
      s.init_gyro_bias_sigma, s.init_accel_bias_sigma, s.init_accel_bias_sigma;
  b.cov = sd.cwiseProduct(sd).asDiagonal();
  return b;
}

}  // namespace ctxfuse::pipelines::region_imm

// Dynamic alignment from position fixes, for every platform (a car, a pedestrian, a ground
// robot) and every pipeline (GNSS/INS, the region IMM, the UWB/IMU filters): position,
// horizontal velocity and heading of a platform that moves along its own forward axis, from
// the fixes alone, with covariances that follow from the fixes' own.
//
// Fixes are planar (x, y) in any right-handed or left-handed frame the caller chooses; the
// heading is atan2(dy, dx) in that frame (ENU: counter-clockwise from east; (north, east):
// the NED yaw). A fix may carry the receiver's velocity with its covariance.
//
// Heading, first source that qualifies at a fix:
//   1. the receiver's velocity, when it reports one: heading variance = the velocity's
//      cross-track variance / speed^2;
//   2. the longest baseline inside max_span_s, from an older fix more than min_distance_m
//      away to this one: variance = the two fixes' cross-track variance / length^2; with
//      straight_track, every fix between the two must lie on the chord within 3 sigma (a
//      turn between them makes the chord's direction no heading of the platform's).
// It is accepted once its 1-sigma is below max_heading_sigma. The velocity is the receiver's
// (source 1) or the displacement over the latest baseline of at least velocity_baseline_s
// (the long baseline's mean lags while the platform accelerates). Each output variance is
// floored (the platform may have turned or changed speed between the fixes).
// Fixed storage: fixes faster than kCapacity per span are thinned to the newest.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <optional>
#include <string>

#include "ctxfuse/core/error.hpp"

namespace ctxfuse::models {

struct AlignmentOptions {
  double max_span_s = 10.0;          // [s] how far back a baseline may reach
  double min_distance_m = 5.0;       // [m] shortest baseline
  double max_heading_sigma = 0.087;  // [rad] accepted once the heading 1-sigma is below (5 deg)
  double velocity_baseline_s = 1.0;  // [s] shortest baseline of the velocity (source 2)
  bool straight_track = false;       // baselines only over fixes on their chord (3 sigma)
  // Floors of the output's standard deviations.
  double position_sigma_floor_m = 0.0;
  double velocity_sigma_floor_mps = 0.0;
  double heading_sigma_floor = 0.0;  // [rad]

  /// Usable, or which option is out of range (DynamicAligner's constructor refuses it).
  SettingCheck check() const {
    auto nonneg = [](double v) { return std::isfinite(v) && v >= 0.0; };
    if (!(std::isfinite(max_span_s) && max_span_s > 0.0)) return SettingCheck::refuse("alignment max_span_s must be finite and > 0");
    if (!nonneg(min_distance_m)) return SettingCheck::refuse("alignment min_distance_m must be finite and >= 0");
    if (!(std::isfinite(max_heading_sigma) && max_heading_sigma > 0.0)) return SettingCheck::refuse("alignment max_heading_sigma must be finite and > 0");
    if (!nonneg(velocity_baseline_s)) return SettingCheck::refuse("alignment velocity_baseline_s must be finite and >= 0");
    if (!nonneg(position_sigma_floor_m) || !nonneg(velocity_sigma_floor_mps) || !nonneg(heading_sigma_floor))
      return SettingCheck::refuse("alignment floors must be finite and >= 0");
    return {};
  }
};

/// One position fix offered to the aligner, optionally with the receiver's velocity.
struct PlanarFix {
  double t = 0.0;
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
  Eigen::Matrix2d cov = Eigen::Matrix2d::Identity();
  bool has_velocity = false;
  Eigen::Vector2d v = Eigen::Vector2d::Zero();
  Eigen::Matrix2d v_cov = Eigen::Matrix2d::Identity();
};

enum class HeadingSource { baseline, receiver_velocity };

inline const char* name_of(HeadingSource s) { return s == HeadingSource::baseline ? "baseline" : "receiver_velocity"; }

/// Position, velocity and heading at time t, with their covariances.
struct PlanarAlignment {
  double t = 0.0;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  Eigen::Matrix2d position_cov = Eigen::Matrix2d::Identity();
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();
  Eigen::Matrix2d velocity_cov = Eigen::Matrix2d::Identity();
  double heading = 0.0;  // [rad] atan2(dy, dx) in the fixes' frame
  double heading_var = 1.0;
  HeadingSource source = HeadingSource::baseline;
  double baseline_m = 0.0, baseline_s = 0.0;  // the heading's baseline (0 for the receiver's velocity)
};

class DynamicAligner {
 public:
  static constexpr std::size_t kCapacity = 128;

  DynamicAligner() = default;
  /// Options that o.check() refuses are a setting error (core/error.hpp).
  explicit DynamicAligner(const AlignmentOptions& o) : o_(o) {
    ctxfuse::detail::require_setting(o.check(), "DynamicAligner");
  }

  /// Forgets every fix offered (a restart aligns afresh).
  void reset() { first_ = count_ = 0; }
  const AlignmentOptions& options() const { return o_; }

  std::optional<PlanarAlignment> add(double t, const Eigen::Vector2d& p, const Eigen::Matrix2d& cov) {
    PlanarFix f;
    f.t = t;
    f.p = p;
    f.cov = cov;
    return add(f);
  }

  /// Offers one fix; returns the alignment at its time when it qualifies. Non-finite fixes and
  /// fixes not after the previous one are ignored (a non-finite velocity is dropped, the
  /// position kept).
  std::optional<PlanarAlignment> add(PlanarFix f) {
    if (!std::isfinite(f.t) || !f.p.allFinite() || !f.cov.allFinite()) return std::nullopt;
    if (count_ > 0 && !(f.t > at(count_ - 1).t)) return std::nullopt;
    f.has_velocity = f.has_velocity && f.v.allFinite() && f.v_cov.allFinite();
    push(f);
    const PlanarFix& now = at(count_ - 1);
    const double max_var = o_.max_heading_sigma * o_.max_heading_sigma;
    if (now.has_velocity) {
      const double speed = now.v.norm();
      if (speed > 0.0) {
        const Eigen::Vector2d across(-now.v.y() / speed, now.v.x() / speed);
        const double var = across.dot(now.v_cov * across) / (speed * speed);
        if (var <= max_var) {
          PlanarAlignment a = common(now);
          a.velocity = now.v;
          a.velocity_cov = now.v_cov;
          a.heading = std::atan2(now.v.y(), now.v.x());
          a.heading_var = var;
          a.source = HeadingSource::receiver_velocity;
          return floored(a);
        }
      }
    }
    for (std::size_t k = 0; k + 1 < count_; ++k) {
      const PlanarFix& a = at(k);
      const Eigen::Vector2d d = now.p - a.p;
      const double len = d.norm();
      if (len <= o_.min_distance_m) continue;
      const Eigen::Vector2d across(-d.y() / len, d.x() / len);
      const double var = across.dot((a.cov + now.cov) * across) / (len * len);
      if (var > max_var) continue;
      if (o_.straight_track && !on_chord(k, across)) continue;
      PlanarAlignment out = common(now);
      set_velocity(out, a);
      out.heading = std::atan2(d.y(), d.x());
      out.heading_var = var;
      out.source = HeadingSource::baseline;
      out.baseline_m = len;
      out.baseline_s = now.t - a.t;
      return floored(out);
    }
    return std::nullopt;
  }

 private:
  PlanarAlignment common(const PlanarFix& now) const {
    PlanarAlignment a;
    a.t = now.t;
    a.position = now.p;
    a.position_cov = now.cov;
    return a;
  }
  /// Every fix strictly between at(k) and the newest lies within 3 sigma of their chord.
  bool on_chord(std::size_t k, const Eigen::Vector2d& across) const {
    const PlanarFix& a = at(k);
    for (std::size_t j = k + 1; j + 1 < count_; ++j) {
      const PlanarFix& m = at(j);
      const double r = across.dot(m.p - a.p);
      const double var = across.dot((m.cov + a.cov) * across);
      if (r * r > 9.0 * var) return false;
    }
    return true;
  }
  /// Velocity over the latest baseline of at least velocity_baseline_s (else from `oldest`).
  void set_velocity(PlanarAlignment& out, const PlanarFix& oldest) const {
    const PlanarFix& b = at(count_ - 1);
    const PlanarFix* v0 = &oldest;
    for (std::size_t k = count_ - 1; k-- > 0;)
      if (b.t - at(k).t >= o_.velocity_baseline_s) {
        v0 = &at(k);
        break;
      }
    const double dt = b.t - v0->t;
    out.velocity = (b.p - v0->p) / dt;
    out.velocity_cov = (b.cov + v0->cov) / (dt * dt);
  }
  PlanarAlignment floored(PlanarAlignment a) const {
    const double p2 = o_.position_sigma_floor_m * o_.position_sigma_floor_m;
    const double v2 = o_.velocity_sigma_floor_mps * o_.velocity_sigma_floor_mps;
    for (int i = 0; i < 2; ++i) {
      a.position_cov(i, i) = std::max(a.position_cov(i, i), p2);
      a.velocity_cov(i, i) = std::max(a.velocity_cov(i, i), v2);
    }
    a.heading_var = std::max(a.heading_var, o_.heading_sigma_floor * o_.heading_sigma_floor);
    return a;
  }
  // The fixes of the last max_span_s, oldest first, in a ring of fixed capacity.
  const PlanarFix& at(std::size_t k) const { return ring_[(first_ + k) % kCapacity]; }
  void push(const PlanarFix& f) {
    while (count_ > 0 && f.t - at(0).t > o_.max_span_s) drop_oldest();
    if (count_ == kCapacity) drop_oldest();
    ring_[(first_ + count_) % kCapacity] = f;
    ++count_;
  }
  void drop_oldest() {
    first_ = (first_ + 1) % kCapacity;
    --count_;
  }
  AlignmentOptions o_{};
  std::array<PlanarFix, kCapacity> ring_{};
  std::size_t first_ = 0, count_ = 0;
};

}  // namespace ctxfuse::models

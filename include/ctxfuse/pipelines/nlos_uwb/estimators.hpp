// Estimators of the NLOS-robust UWB pipeline. The run loop (run.hpp) takes the estimator as a
// template parameter; anything with this shape plugs in:
//
//   bool started() const;                        // has a belief
//   Status start(double t, Vector2d p, Matrix2d P);  // from a snapshot fix (position, cov)
//   Status predict_to(double t);                 // motion model up to t (t >= time())
//   Status apply_epoch(ranges, attach, statuses);  // the epoch's ranges with the policy's mask;
//                                                  // statuses[i]: range i's outcome (attached
//                                                  // ones); the return: the step as a whole
//   void stop();                                 // forget the belief (restart from a fix)
//   double time() const; Vector2d position() const; Vector2d velocity() const;
//
// - RangeEkf<Gate>: the EKF of the gated fusion: constant velocity (the Hanyang recordings
//   have no IMU, so a motion model takes the IMU factor's place) and one sequential update per
//   attached range, each through the innovation gate `Gate` (policies/gating.hpp).
// - MotionModelOnly: the same prediction started from the first fix and never corrected:
//   the "IMU only" baseline of the paper with the motion model in the IMU's place.
// - RangeSmoother (smoother.hpp): the fixed-lag smoother of filters/fixed_lag.hpp.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>  // determinant()

#include <cmath>
#include <span>
#include <string_view>
#include <type_traits>

#include "ctxfuse/core/block_sparsity.hpp"
#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/pipelines/nlos_uwb/settings.hpp"
#include "ctxfuse/policies/gating.hpp"

namespace ctxfuse::pipelines::nlos_uwb {

using PlanarLayout = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;

/// Range from a tag at a known height (the planar state's "p" at z = tag_height) to an anchor
/// at a known 3-D position: z = |(p, h) - a| + noise.
struct RangeAtHeight {
  static constexpr int dim = 1;
  static constexpr auto jacobian_columns = column_pattern<PlanarLayout>({std::string_view("p")});
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();
  double tag_height = 0.0;
  double sigma = 0.1;

  Vector<1> predict(const Vector<4>& x, Matrix<1, 4>* H) const {
    const Eigen::Vector3d d(x(0) - anchor.x(), x(1) - anchor.y(), tag_height - anchor.z());
    const double r = d.norm();
    if (H) {
      H->setZero();
      if (r > 0.0) {  // undefined on the anchor itself: a zero row makes the update a no-op
        (*H)(0, 0) = d.x() / r;
        (*H)(0, 1) = d.y() / r;
      }
    }
    return Vector<1>(r);
  }
  SquareMatrix<1> noise(const Vector<4>&) const { return SquareMatrix<1>(sigma * sigma); }
  Problem check(const Vector<1>& z) const { return z(0) < 0.0 ? Problem::measurement_out_of_domain : Problem::none; }
};

/// The clock's checks of predict_to(t): started, t finite and not before the clock.
inline Status clock_check(bool started, double now, double t) {
  if (!started) return Status::invalid(Problem::time_not_set);
  if (!std::isfinite(t)) return Status::invalid(Problem::non_finite_dt);
  return t < now ? Status::invalid(Problem::out_of_order_time) : Status{};
}

/// A range every estimator refuses before use: non-finite, not positive, beyond max_range_m.
inline Problem range_problem(const messages::UwbRange& r, const Settings& s) {
  if (!r.anchor_position.allFinite() || !std::isfinite(r.range_m)) return Problem::non_finite_measurement;
  if (!(r.range_m > 0.0 && r.range_m <= s.max_range_m)) return Problem::measurement_out_of_domain;
  return Problem::none;
}

/// An EKF's epoch: each attached range at its own time, in order (predict_to, then update;
/// statuses[i] its outcome), then the clock to the epoch's last range. A refused prediction
/// ends the epoch with its status.
template <class Ekf>
Status apply_ranges_in_order(Ekf& ekf, std::span<const messages::UwbRange> epoch, std::span<const bool> attach, std::span<Status> statuses) {
  for (std::size_t i = 0; i < epoch.size(); ++i) {
    if (!attach[i]) continue;
    if (const Status p = ekf.predict_to(epoch[i].t); !p.accepted()) return p;
    statuses[i] = ekf.update(epoch[i]);
  }
  return ekf.predict_to(epoch.back().t);
}

/// False for an estimator that declares `uses_ranges = false` (the motion-model baseline).
template <class E>
inline constexpr bool kUsesRanges = [] {
  if constexpr (requires { E::uses_ranges; })
    return static_cast<bool>(E::uses_ranges);
  else
    return true;
}();

/// The starting belief from a snapshot fix: its position and covariance, velocity zero within
/// settings.initial_speed_sigma_mps. Refuses non-finite or indefinite input.
inline Status initial_belief(const Eigen::Vector2d& p, const Eigen::Matrix2d& P, const Settings& s, Gaussian<4>& out) {
  if (!p.allFinite() || !P.allFinite()) return Status::invalid(Problem::non_finite_measurement);
  if (!(P(0, 0) > 0.0 && P(1, 1) > 0.0 && P.determinant() > 0.0)) return Status::invalid(Problem::covariance_not_positive_definite);
  out.mean << p, 0.0, 0.0;
  out.cov.setZero();
  out.cov.topLeftCorner<2, 2>() = P;
  out.cov.bottomRightCorner<2, 2>() = Eigen::Matrix2d::Identity() * s.initial_speed_sigma_mps * s.initial_speed_sigma_mps;
  return Status{};
}

/// The innovation gate of the settings (a chi-square gate at settings.gate_probability).
template <GatePolicy Gate>
Gate make_gate(const Settings& s) {
  if constexpr (std::is_same_v<Gate, policies::ChiSquareGate>)
    return policies::ChiSquareGate(s.gate_probability);
  else
    return Gate{};
}

namespace detail {

/// Belief, clock and motion model shared by the EKF and the motion-model-only baseline.
class PlanarCvBelief {
 public:
  explicit PlanarCvBelief(const Settings& s) : settings_(s) { motion_.accel_psd = s.accel_psd; }

  bool started() const { return started_; }
  double time() const { return t_; }
  Eigen::Vector2d position() const { return belief_.mean.head<2>(); }
  Eigen::Vector2d velocity() const { return belief_.mean.tail<2>(); }
  const Gaussian<4>& belief() const { return belief_; }

  Status start(double t, const Eigen::Vector2d& p, const Eigen::Matrix2d& P) {
    if (!std::isfinite(t)) return Status::invalid(Problem::non_finite_dt);
    Gaussian<4> b;
    if (const Status s = initial_belief(p, P, settings_, b); !s.accepted()) return s;
    belief_ = b;
    t_ = t;
    started_ = true;
    return Status{};
  }

  /// Predicts to t; t equal to the clock is a no-op, t before it is refused (state unchanged).
  Status predict_to(double t) {
    if (const Status c = clock_check(started_, t_, t); !c.accepted() || t == t_) return c;
    const Status s = ekf::predict(motion_, belief_, NoInput{}, t - t_);
    if (s.accepted()) t_ = t;
    return s;
  }

  /// Forgets the belief (after a failed step: the next fix starts again).
  void stop() { started_ = false; }

 protected:
  Settings settings_;
  models::ConstantVelocity<PlanarLayout, 2> motion_;
  Gaussian<4> belief_;
  double t_ = 0.0;
  bool started_ = false;
};

}  // namespace detail

template <GatePolicy Gate = policies::ChiSquareGate>
class RangeEkf : public detail::PlanarCvBelief {
 public:
  explicit RangeEkf(const Settings& s) : PlanarCvBelief(s), gate_(make_gate<Gate>(s)) {}
  RangeEkf(const Settings& s, Gate gate) : PlanarCvBelief(s), gate_(gate) {}

  Status update(const messages::UwbRange& r) {
    if (!started_) return Status::invalid(Problem::time_not_set);
    if (const Problem p = range_problem(r, settings_); p != Problem::none) return Status::invalid(p);
    const RangeAtHeight h{r.anchor_position, settings_.tag_height_m, settings_.range_sigma_m};
    return ekf::update<4>(h, belief_, Vector<1>(r.range_m), gate_);
  }

  Status apply_epoch(std::span<const messages::UwbRange> epoch, std::span<const bool> attach, std::span<Status> statuses) {
    return apply_ranges_in_order(*this, epoch, attach, statuses);
  }

 private:
  Gate gate_;
};

/// Baseline: the motion model from the first fix on, no range ever used after it.
class MotionModelOnly : public detail::PlanarCvBelief {
 public:
  using PlanarCvBelief::PlanarCvBelief;
  static constexpr bool uses_ranges = false;  // the run loop never offers it a range
  Status apply_epoch(std::span<const messages::UwbRange> epoch, std::span<const bool>, std::span<Status>) {
    return predict_to(epoch.back().t);
  }
};

}  // namespace ctxfuse::pipelines::nlos_uwb

// Geodetic strapdown INS as an error-state process model: position latitude/longitude/height,
// velocity north/east/down, attitude body -> NED as a unit quaternion, gyro and accelerometer
// biases as first-order Gauss-Markov processes. The error layout is Ins15Layout (p [m NED],
// v, theta [body-frame rotation vector], bg, ba); the state is a BlockState over it, so its
// inject/difference/reset Jacobian come from the blocks' retractions (core/block_state.hpp)
// and an augmentation (models/ins_augment.hpp) adds blocks without touching this file.
//
// Two mechanisations, chosen at compile time:
//   SimplifiedStrapdown: the smartphone paper's -- no earth rate, no transport rate, no coning
//                        or sculling; q+ = q Exp(dtheta), v+ = v + C dv + g dt.
//   FullStrapdown:       earth rotation and transport rate on attitude and velocity (Coriolis),
//                        two-sample coning and sculling from consecutive increments.
//
// Intended use with io/replay.hpp (a later pipeline builds this; nothing here reads files):
//   using Ins20 = Augmented<InsNavModel<>, StateBlock<"mount", 2>, StateBlock<"lever", 3>>;  // ins_augment.hpp
//   ImuInput imu{mounting_rotation(r, p, y), delay};   // ins_input.hpp
//   Before the replay, shift each messages::ImuSample's stamp with imu.apply_delay; start the filter
//   from a DynamicAligner (alignment.hpp) fed with the messages::GnssFix positions. Handler:
//     propagate(u, dt):  BodyIncrements inc;
//                        if (imu.from_rates(u.gyro, u.accel, dt, inc).accepted())
//                          eskf::predict(model, belief, inc, dt, opts, &F);  rts.predicted(F);
//     on(messages::ImuSample): StaticDetector::push(raw rates); ZeroVelocity + Heading (ZIHR) while
//                        static, NonHolonomic[WithSpeed] while moving (ins_updates.hpp)
//     on(messages::GnssFix):   GnssGeodeticPosition (R from geodetic_position_noise of the fix's
//                        ned_from_enu_cov) and GnssVelocity, each with a ChiSquareGate; then
//                        rts.record(t, prior, belief) (filters/rts.hpp) for the smoother.
// Time steps come from the stamps (irregular sampling at any rate is fine); a dt <= 0 or a
// non-finite one is refused (ImuInput, and the filter) with a Status and nothing changes.
#pragma once

#include <cmath>

#include "ctxfuse/core/block_state.hpp"
#include "ctxfuse/core/so3.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/models/earth.hpp"
#include "ctxfuse/models/ins.hpp"

namespace ctxfuse::models {

/// Angle [rad] and velocity [m/s] increments in the body frame over one step, and the previous
/// step's (for coning and sculling; `has_previous` false on the first step).
struct BodyIncrements {
  Eigen::Vector3d dtheta = Eigen::Vector3d::Zero();
  Eigen::Vector3d dv = Eigen::Vector3d::Zero();
  Eigen::Vector3d prev_dtheta = Eigen::Vector3d::Zero();
  Eigen::Vector3d prev_dv = Eigen::Vector3d::Zero();
  bool has_previous = false;
  bool is_finite() const { return all_finite(dtheta) && all_finite(dv) && all_finite(prev_dtheta) && all_finite(prev_dv); }
  double max_abs() const { return std::max(dtheta.cwiseAbs().maxCoeff(), dv.cwiseAbs().maxCoeff()); }
};

using NavState = BlockState<Ins15Layout, earth::GeodeticRetraction, VectorRetraction<3>, So3Retraction,
                            VectorRetraction<3>, VectorRetraction<3>>;

struct SimplifiedStrapdown {
  static constexpr bool earth_terms = false;
};
struct FullStrapdown {
  static constexpr bool earth_terms = true;
};

/// Heading (yaw) of a body -> NED rotation [rad], and its derivative with respect to the
/// body-frame attitude error theta (C_true = C Exp(theta)).
inline double heading_of(const Eigen::Matrix3d& C) { return std::atan2(C(1, 0), C(0, 0)); }
inline Eigen::RowVector3d heading_jacobian(const Eigen::Matrix3d& C) {
  // dC = C [theta]x, whose first column is C (theta x e_x) = C (0, theta_z, -theta_y):
  // dC(0,0) = C(0,1) th_z - C(0,2) th_y and dC(1,0) = C(1,1) th_z - C(1,2) th_y.
  const double n2 = C(0, 0) * C(0, 0) + C(1, 0) * C(1, 0);
  Eigen::RowVector3d J;
  J(0) = 0.0;
  J(1) = (-C(0, 0) * C(1, 2) + C(1, 0) * C(0, 2)) / n2;
  J(2) = (C(0, 0) * C(1, 1) - C(1, 0) * C(0, 1)) / n2;
  return J;
}

template <class Mechanisation = SimplifiedStrapdown>
struct InsNavModel : BlockRetractionOf<NavState> {
  using ErrorLayout = Ins15Layout;
  using State = NavState;
  using Input = BodyIncrements;
  static constexpr int dim = ErrorLayout::size;
  static constexpr bool earth_terms = Mechanisation::earth_terms;

  // The Coriolis term makes the v-v block a dense block in the full mechanisation, and the
  // sculling term (1/2 dtheta x dv, dtheta = gyro increment - bg dt) couples v and p to bg.
  static constexpr auto transition_blocks = [] {
    if constexpr (earth_terms)
      return block_pattern<ErrorLayout>({
          {"p", "p", kIdentity}, {"p", "v", kDiagonal}, {"p", "theta"}, {"p", "bg"}, {"p", "ba"},
          {"v", "v"}, {"v", "theta"}, {"v", "bg"}, {"v", "ba"},
          {"theta", "theta"}, {"theta", "bg"},
          {"bg", "bg", kDiagonal},
          {"ba", "ba", kDiagonal},
      });
    else
      return block_pattern<ErrorLayout>({
          {"p", "p", kIdentity}, {"p", "v", kDiagonal}, {"p", "theta"}, {"p", "ba"},
          {"v", "v", kIdentity}, {"v", "theta"}, {"v", "ba"},
          {"theta", "theta"}, {"theta", "bg"},
          {"bg", "bg", kDiagonal},
          {"ba", "ba", kDiagonal},
      });
  }();
  static constexpr auto reset_blocks = block_reset_pattern<NavState>();

  double gyro_noise_density = 1e-3;   // [rad/s/sqrt(Hz)] angle random walk
  double accel_noise_density = 1e-2;  // [m/s^2/sqrt(Hz)] velocity random walk
  GaussMarkov gyro_bias{1e-5};
  GaussMarkov accel_bias{1e-4};

  /// The nominal propagation. The error transition F neglects the dependence of the earth and
  /// transport rates and of gravity on the position and velocity errors (terms of order
  /// earth rate / earth radius, ~1e-11 /s per metre, and 2 g / R ~ 3e-6 /s^2 on the height):
  /// they matter over hours, not over GNSS outages of seconds to minutes.
  State predict(const State& x, const Input& u, double dt, SquareMatrix<dim>* F) const {
    return step(x, u, dt, F);
  }
  /// The same with F written into any writable dim x dim expression (an augmented model's
  /// top-left corner, models/ins_augment.hpp), zeros included.
  template <class Derived>
  State predict(const State& x, const Input& u, double dt, Eigen::MatrixBase<Derived>& F) const {
    return step(x, u, dt, &F);
  }

  SquareMatrix<dim> noise(const State&, const Input&, double dt) const {
    return strapdown_noise<ErrorLayout>(accel_noise_density, gyro_noise_density, gyro_bias, accel_bias, dt);
  }
  /// The same written into any writable dim x dim expression, zeros included.
  template <class Derived>
  void noise(const State&, const Input&, double dt, Eigen::MatrixBase<Derived>& Q) const {
    strapdown_noise_into<ErrorLayout>(accel_noise_density, gyro_noise_density, gyro_bias, accel_bias, dt, Q);
  }

 private:
  // FOut: SquareMatrix<dim> or any writable dim x dim Eigen expression; nullptr for no F.
  template <class FOut>
  State step(const State& x, const Input& u, double dt, FOut* F) const {
    using L = ErrorLayout;
    const Eigen::Vector3d& llh = x.get<"p">();
    const Eigen::Vector3d& v = x.get<"v">();
    const Eigen::Quaterniond& q = x.get<"theta">();
    const Eigen::Vector3d& bg = x.get<"bg">();
    const Eigen::Vector3d& ba = x.get<"ba">();

    Eigen::Vector3d dtheta = u.dtheta - bg * dt;
    Eigen::Vector3d dv = u.dv - ba * dt;
    Eigen::Vector3d dv_rot = dv;
    // d(dv_rot)/d(dv) and d(corrected dtheta)/d(dtheta), for F.
    Eigen::Matrix3d dv_rot_per_dv = Eigen::Matrix3d::Identity();
    Eigen::Matrix3d dtheta_per_dtheta = Eigen::Matrix3d::Identity();
    if constexpr (earth_terms) {
      dv_rot_per_dv += 0.5 * so3::skew(dtheta);
      if (u.has_previous) {
        dtheta_per_dtheta += so3::skew(u.prev_dtheta) / 12.0;
        dv_rot_per_dv += so3::skew(u.prev_dtheta) / 12.0;
        // Two-sample coning and sculling (previous increment with the current one).
        dtheta += u.prev_dtheta.cross(dtheta) / 12.0;
        dv_rot += 0.5 * dtheta.cross(dv) + (u.prev_dtheta.cross(dv) + u.prev_dv.cross(dtheta)) / 12.0;
      } else {
        dv_rot += 0.5 * dtheta.cross(dv);
      }
    }
    const Eigen::Matrix3d C = q.toRotationMatrix();
    const double g = earth::normal_gravity(llh(0), llh(2));
    Eigen::Vector3d dv_n = C * dv_rot + Eigen::Vector3d(0.0, 0.0, g * dt);
    Eigen::Vector3d w_ie = Eigen::Vector3d::Zero(), w_en = Eigen::Vector3d::Zero();
    if constexpr (earth_terms) {
      w_ie = earth::earth_rate_ned(llh(0));
      w_en = earth::transport_rate_ned(llh(0), llh(2), v);
      // The NED frame turns by zeta = (w_ie + w_en) dt over the step: the velocity increment,
      // resolved at the start of the step, is rotated by half of it (mid-step frame).
      const Eigen::Vector3d zeta = (w_ie + w_en) * dt;
      dv_n -= 0.5 * zeta.cross(C * dv_rot);
      dv_n -= (2.0 * w_ie + w_en).cross(v) * dt;
    }

    State out;
    const Eigen::Vector3d v_new = v + dv_n;
    out.get<"v">() = v_new;
    // Position: trapezoidal velocity, metres to radians at the start of the step.
    out.get<"p">() = llh + (0.5 * (v + v_new) * dt).cwiseQuotient(earth::ned_per_llh(llh(0), llh(2)));
    Eigen::Quaterniond q_step;
    Eigen::Matrix3d Jr_step;
    so3::exp_quat_and_right_jacobian(dtheta, q_step, Jr_step);
    Eigen::Quaterniond q_new = q * q_step;
    if constexpr (earth_terms) q_new = so3::exp_quat(Eigen::Vector3d(-(w_ie + w_en) * dt)) * q_new;
    out.get<"theta">() = q_new.normalized();
    const double kg = gyro_bias.decay(dt), ka = accel_bias.decay(dt);
    out.get<"bg">() = kg * bg;
    out.get<"ba">() = ka * ba;

    if (F) {
      F->setZero();
      F->diagonal().setOnes();
      // The specific force as integrated (with the rotation compensation in the full one).
      const Eigen::Vector3d a = dv_rot / dt;
      const Eigen::Matrix3d C_ax = C * so3::skew(a);
      L::cov<"p", "v">(*F).diagonal().setConstant(dt);
      L::cov<"p", "theta">(*F) = -0.5 * dt * dt * C_ax;
      L::cov<"p", "ba">(*F) = -0.5 * dt * dt * C * dv_rot_per_dv;
      if constexpr (earth_terms) {
        L::cov<"v", "v">(*F) = Eigen::Matrix3d::Identity() - dt * so3::skew(2.0 * w_ie + w_en);
        // d(1/2 dtheta x dv + prev_dv x dtheta / 12)/dbg = dt (1/2 [dv]x - [prev_dv]x / 12),
        // in v and half a step of it in p.
        const Eigen::Matrix3d C_dvx = C * (so3::skew(dv) - so3::skew(u.prev_dv) / 6.0);
        L::cov<"v", "bg">(*F) = 0.5 * dt * C_dvx;
        L::cov<"p", "bg">(*F) = 0.25 * dt * dt * C_dvx;
      }
      L::cov<"v", "theta">(*F) = -dt * C_ax;
      L::cov<"v", "ba">(*F) = -dt * C * dv_rot_per_dv;
      L::cov<"theta", "theta">(*F) = q_step.toRotationMatrix().transpose();
      L::cov<"theta", "bg">(*F) = -dt * Jr_step * dtheta_per_dtheta;
      L::cov<"bg", "bg">(*F).diagonal().setConstant(kg);
      L::cov<"ba", "ba">(*F).diagonal().setConstant(ka);
    }
    return out;
  }
};

}  // namespace ctxfuse::models

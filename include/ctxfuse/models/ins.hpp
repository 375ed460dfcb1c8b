// Strapdown inertial navigation as an error-state process model (15 states), and the GNSS
// position measurement with a lever arm.
//
// Frames: a local-level navigation frame n (any right-handed one; gravity is a parameter, so
// ENU uses (0, 0, -g) and NED (0, 0, +g)) and the body frame b of the IMU. Simplified
// mechanisation as in the smartphone paper: no earth rotation, no transport rate, no coning or
// sculling corrections -- right for low-cost IMUs over short baselines.
//
// Error state (local attitude error, true = nominal [+] error):
//   p_true = p + dp, v_true = v + dv, q_true = q * Exp(dtheta), bg_true = bg + dbg, ...
#pragma once

#include <cmath>
#include <limits>

#include "ctxfuse/core/block_sparsity.hpp"
#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/so3.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"
#include "ctxfuse/messages/sensors.hpp"

namespace ctxfuse::models {

/// The IMU sample (messages/sensors.hpp): angular rate [rad/s] and specific force [m/s^2], both
/// in the body frame; its stamp is not read (the step's dt is), increments are refused.
using ImuSample = messages::ImuSample;

struct InsState {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  // body -> navigation
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();
  Eigen::Vector3d ba = Eigen::Vector3d::Zero();
};

using Ins15Layout = Layout<StateBlock<"p", 3>, StateBlock<"v", 3>, StateBlock<"theta", 3>, StateBlock<"bg", 3>, StateBlock<"ba", 3>>;

/// First-order Gauss-Markov bias: b+ = exp(-dt/tau) b + w, with driving-noise density sigma
/// [unit/s/sqrt(Hz)... i.e. unit/sqrt(s)]; tau = infinity is a random walk.
struct GaussMarkov {
  double density = 0.0;
  double tau = std::numeric_limits<double>::infinity();

  double decay(double dt) const { return std::isfinite(tau) ? std::exp(-dt / tau) : 1.0; }
  double variance(double dt) const {
    if (!std::isfinite(tau)) return density * density * dt;
    return density * density * tau / 2.0 * (1.0 - std::exp(-2.0 * dt / tau));
  }
};

/// Discrete process noise of a strapdown INS over any error layout with blocks p, v, theta, bg
/// and ba. White specific-force noise enters v directly and p through the half-step; isotropic
/// noise is unchanged by the rotation to the navigation frame. Written into any writable
/// L::size x L::size expression (an augmented model's top-left corner), zeros included.
template <class L, class Derived>
void strapdown_noise_into(double accel_noise_density, double gyro_noise_density, const GaussMarkov& gyro_bias,
                          const GaussMarkov& accel_bias, double dt, Eigen::MatrixBase<Derived>& Q) {
  Q.setZero();
  const double qa = accel_noise_density * accel_noise_density;
  L::template cov<"p">(Q).diagonal().setConstant(qa * dt * dt * dt / 3.0);
  L::template cov<"p", "v">(Q).diagonal().setConstant(qa * dt * dt / 2.0);
  L::template cov<"v", "p">(Q).diagonal().setConstant(qa * dt * dt / 2.0);
  L::template cov<"v">(Q).diagonal().setConstant(qa * dt);
  L::template cov<"theta">(Q).diagonal().setConstant(gyro_noise_density * gyro_noise_density * dt);
  L::template cov<"bg">(Q).diagonal().setConstant(gyro_bias.variance(dt));
  L::template cov<"ba">(Q).diagonal().setConstant(accel_bias.variance(dt));
}

template <class L>
SquareMatrix<L::size> strapdown_noise(double accel_noise_density, double gyro_noise_density, const GaussMarkov& gyro_bias,
                                      const GaussMarkov& accel_bias, double dt) {
  SquareMatrix<L::size> Q;
  strapdown_noise_into<L>(accel_noise_density, gyro_noise_density, gyro_bias, accel_bias, dt, Q);
  return Q;
}

struct Ins15Model {
  using ErrorLayout = Ins15Layout;
  using State = InsState;
  using Input = ImuSample;
  static constexpr int dim = ErrorLayout::size;

  // Where F and the reset Jacobian G can be non-zero (see core/block_sparsity.hpp).
  static constexpr auto transition_blocks = block_pattern<ErrorLayout>({
      {"p", "p", kIdentity}, {"p", "v", kDiagonal}, {"p", "theta"}, {"p", "ba"},
      {"v", "v", kIdentity}, {"v", "theta"}, {"v", "ba"},
      {"theta", "theta"}, {"theta", "bg"},
      {"bg", "bg", kDiagonal},
      {"ba", "ba", kDiagonal},
  });
  static constexpr auto reset_blocks = block_pattern<ErrorLayout>({
      {"p", "p", kIdentity}, {"v", "v", kIdentity}, {"theta", "theta"}, {"bg", "bg", kIdentity}, {"ba", "ba", kIdentity},
  });

  Eigen::Vector3d gravity{0.0, 0.0, -9.80665};  // ENU by default
  double gyro_noise_density = 1e-3;             // [rad/s/sqrt(Hz)] angle random walk
  double accel_noise_density = 1e-2;            // [m/s^2/sqrt(Hz)] velocity random walk
  GaussMarkov gyro_bias{1e-5};
  GaussMarkov accel_bias{1e-4};
  // Rates above these are not a vehicle; they are a broken sample.
  double max_gyro = 35.0;    // [rad/s] (2000 deg/s)
  double max_accel = 400.0;  // [m/s^2] (~40 g)

  Problem check_input(const ImuSample& u) const {
    if (u.increments) return Problem::input_wrong_kind;
    if (u.gyro.cwiseAbs().maxCoeff() > max_gyro || u.accel.cwiseAbs().maxCoeff() > max_accel)
      return Problem::input_magnitude;
    return Problem::none;
  }

  State predict(const State& x, const Input& u, double dt, SquareMatrix<dim>* F) const {
    using L = ErrorLayout;
    const Eigen::Vector3d w = u.gyro - x.bg;
    const Eigen::Vector3d a = u.accel - x.ba;
    const Eigen::Matrix3d R = x.q.toRotationMatrix();
    const Eigen::Vector3d acc_n = R * a + gravity;

    State out;
    out.p = x.p + x.v * dt + 0.5 * acc_n * dt * dt;
    out.v = x.v + acc_n * dt;
    const Eigen::Vector3d wdt = w * dt;
    Eigen::Quaterniond q_step;
    Eigen::Matrix3d Jr_step;
    so3::exp_quat_and_right_jacobian(wdt, q_step, Jr_step);
    out.q = (x.q * q_step).normalized();
    const double kg = gyro_bias.decay(dt), ka = accel_bias.decay(dt);
    out.bg = kg * x.bg;
    out.ba = ka * x.ba;

    if (F) {
      // Zero fill plus a unit diagonal: Eigen's setIdentity() evaluates i == j per coefficient.
      F->setZero();
      F->diagonal().setOnes();
      const Eigen::Matrix3d R_ax = R * so3::skew(a);
      L::cov<"p", "v">(*F).diagonal().setConstant(dt);
      L::cov<"p", "theta">(*F) = -0.5 * dt * dt * R_ax;
      L::cov<"p", "ba">(*F) = -0.5 * dt * dt * R;
      L::cov<"v", "theta">(*F) = -dt * R_ax;
      L::cov<"v", "ba">(*F) = -dt * R;
      L::cov<"theta", "theta">(*F) = q_step.toRotationMatrix().transpose();
      L::cov<"theta", "bg">(*F) = -dt * Jr_step;
      L::cov<"bg", "bg">(*F).diagonal().setConstant(kg);
      L::cov<"ba", "ba">(*F).diagonal().setConstant(ka);
    }
    return out;
  }

  SquareMatrix<dim> noise(const State&, const Input&, double dt) const {
    return strapdown_noise<ErrorLayout>(accel_noise_density, gyro_noise_density, gyro_bias, accel_bias, dt);
  }

  State inject(const State& x, const Vector<dim>& dx) const {
    using L = ErrorLayout;
    State out;
    out.p = x.p + L::get<"p">(dx);
    out.v = x.v + L::get<"v">(dx);
    out.q = (x.q * so3::exp_quat(L::get<"theta">(dx))).normalized();
    out.bg = x.bg + L::get<"bg">(dx);
    out.ba = x.ba + L::get<"ba">(dx);
    return out;
  }

  Vector<dim> difference(const State& a, const State& b) const {
    using L = ErrorLayout;
    Vector<dim> d;
    L::get<"p">(d) = a.p - b.p;
    L::get<"v">(d) = a.v - b.v;
    L::get<"theta">(d) = so3::log(Eigen::Quaterniond(b.q.conjugate() * a.q));
    L::get<"bg">(d) = a.bg - b.bg;
    L::get<"ba">(d) = a.ba - b.ba;
    return d;
  }

  /// After injecting dx, an error e about the old nominal is e' = Jr(dtheta) e about the new
  /// one in the attitude block (Exp(dtheta + e) = Exp(dtheta) Exp(Jr e)); identity elsewhere.
  /// The usual I - [dtheta/2]x is the first-order truncation of Jr.
  SquareMatrix<dim> reset_jacobian(const State&, const Vector<dim>& dx) const {
    using L = ErrorLayout;
    SquareMatrix<dim> G = SquareMatrix<dim>::Zero();
    G.diagonal().setOnes();
    L::cov<"theta">(G) = so3::right_jacobian(Eigen::Vector3d(L::get<"theta">(dx)));
    return G;
  }

  bool is_finite(const State& x) const {
    return all_finite(x.p) && all_finite(x.v) && all_finite(x.q.coeffs()) && all_finite(x.bg) && all_finite(x.ba);
  }
};

/// GNSS antenna position: z = p + R(q) l_b, with l_b the lever arm from IMU to antenna in the
/// body frame. Works with any error layout that has blocks "p" and "theta" (15- or 20-state).
template <class ErrorLayout = Ins15Layout>
struct GnssPosition {
  static constexpr int dim = 3;
  static constexpr auto jacobian_columns = column_pattern<ErrorLayout>({"p", "theta"});
  Eigen::Vector3d lever_arm = Eigen::Vector3d::Zero();
  SquareMatrix<3> R = SquareMatrix<3>::Identity();

  Vector<3> predict(const InsState& x, Matrix<3, ErrorLayout::size>* H) const {
    const Eigen::Matrix3d C = x.q.toRotationMatrix();
    if (H) {
      H->setZero();
      ErrorLayout::template cols<"p">(*H).setIdentity();
      // d(C Exp(e) l)/de = -C [l]x
      ErrorLayout::template cols<"theta">(*H) = -C * so3::skew(lever_arm);
    }
    return x.p + C * lever_arm;
  }
  SquareMatrix<3> noise(const InsState&) const { return R; }
};

}  // namespace ctxfuse::models

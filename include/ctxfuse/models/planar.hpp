// Planar IMU-driven vehicle model and the measurements of the region paper's sub-models
// (GNSS position, UWB range), plus the wheel-speed / non-holonomic body velocity.
//
// Frame: local ENU, x east, y north; heading psi is the yaw of the body x axis (forward),
// counter-clockwise from east (the simulator's convention, sim/world.hpp). The paper's
// "X right, Y forward" vehicle frame is a fixed rotation of this one; errors are reported in
// ENU. Body axes FLU: the IMU gives the yaw rate (gyro z) and forward/lateral specific force
// (accel x, y); on level ground specific force in the plane is the acceleration.
//
// State (PlanarLayout, 8): p (2) [m], v (2) [m/s, ENU], psi (1) [rad], bg (1) yaw-rate bias
// [rad/s], ba (2) forward/lateral accel bias [m/s^2]. Built from the core Layout so that
// measurement models written on block names ({p}) apply here and to the 15-state INS.
//
// Process (first order over dt, heading at the start of the step):
//   a_n = R(psi) (f - ba),  p+ = p + v dt + a_n dt^2/2,  v+ = v + a_n dt,
//   psi+ = psi + (w - bg) dt,  bg+ = bg,  ba+ = ba  (random walks).
#pragma once

#include <cmath>
#include <numbers>

#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse::models {

using PlanarLayout = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>, StateBlock<"psi", 1>, StateBlock<"bg", 1>, StateBlock<"ba", 2>>;

/// Wraps an angle to (-pi, pi].
inline double wrap_angle(double a) {
  a = std::remainder(a, 2.0 * std::numbers::pi);
  return a <= -std::numbers::pi ? a + 2.0 * std::numbers::pi : a;
}

/// The planar part of one IMU sample.
struct PlanarImu {
  double yaw_rate = 0.0;   // gyro z [rad/s]
  Vector<2> accel = Vector<2>::Zero();  // specific force forward, left [m/s^2]
  bool is_finite() const { return std::isfinite(yaw_rate) && accel.allFinite(); }
  double max_abs() const { return std::max(std::abs(yaw_rate), accel.cwiseAbs().maxCoeff()); }
};

struct PlanarImuModel {
  using L = PlanarLayout;
  using State = Vector<L::size>;
  using Input = PlanarImu;
  static constexpr int dim = L::size;

  double accel_noise_density = 0.05;    // [m/s^2/sqrt(Hz)] white specific-force noise (plus unmodelled)
  double gyro_noise_density = 1e-3;     // [rad/s/sqrt(Hz)]
  double gyro_bias_walk = 1e-5;         // [rad/s/sqrt(s)]
  double accel_bias_walk = 1e-3;        // [m/s^2/sqrt(s)]
  double max_yaw_rate = 10.0;           // [rad/s] beyond this a sample is broken, not a car
  double max_accel = 100.0;             // [m/s^2]

  Problem check_input(const PlanarImu& u) const {
    if (std::abs(u.yaw_rate) > max_yaw_rate || u.accel.cwiseAbs().maxCoeff() > max_accel) return Problem::input_magnitude;
    return Problem::none;
  }

  State predict(const State& x, const Input& u, double dt, SquareMatrix<dim>* F) const {
    const double psi = L::get<"psi">(x)(0);
    const double c = std::cos(psi), s = std::sin(psi);
    Matrix<2, 2> Rot;
    Rot << c, -s, s, c;
    const Vector<2> f = u.accel - L::get<"ba">(x);
    const Vector<2> a = Rot * f;
    State out = x;
    L::get<"p">(out) += L::get<"v">(x) * dt + 0.5 * dt * dt * a;
    L::get<"v">(out) += dt * a;
    L::get<"psi">(out)(0) = wrap_angle(psi + (u.yaw_rate - L::get<"bg">(x)(0)) * dt);
    if (F) {
      F->setIdentity();
      Matrix<2, 2> dRot;  // dR/dpsi
      dRot << -s, -c, c, -s;
      const Vector<2> da_dpsi = dRot * f;
      L::cov<"p", "v">(*F).diagonal().setConstant(dt);
      L::cov<"p", "psi">(*F) = 0.5 * dt * dt * da_dpsi;
      L::cov<"p", "ba">(*F) = -0.5 * dt * dt * Rot;
      L::cov<"v", "psi">(*F) = dt * da_dpsi;
      L::cov<"v", "ba">(*F) = -dt * Rot;
      L::cov<"psi", "bg">(*F)(0, 0) = -dt;
    }
    return out;
  }

  /// a [-] b and x [+] dx with the heading wrapped: what averaging estimates (IMM mixing,
  /// federated fusion) must use so that headings of +179 and -179 deg average to 180, not 0.
  Vector<dim> difference(const State& a, const State& b) const {
    Vector<dim> d = a - b;
    L::get<"psi">(d)(0) = wrap_angle(d(L::offset<"psi">()));
    return d;
  }
  State inject(const State& x, const Vector<dim>& dx) const {
    State out = x + dx;
    L::get<"psi">(out)(0) = wrap_angle(out(L::offset<"psi">()));
    return out;
  }

  SquareMatrix<dim> noise(const State&, const Input&, double dt) const {
    SquareMatrix<dim> Q = SquareMatrix<dim>::Zero();
    const double qa = accel_noise_density * accel_noise_density;
    L::cov<"p">(Q).diagonal().setConstant(qa * dt * dt * dt / 3.0);
    L::cov<"p", "v">(Q).diagonal().setConstant(qa * dt * dt / 2.0);
    L::cov<"v", "p">(Q).diagonal().setConstant(qa * dt * dt / 2.0);
    L::cov<"v">(Q).diagonal().setConstant(qa * dt);
    L::cov<"psi">(Q)(0, 0) = gyro_noise_density * gyro_noise_density * dt;
    L::cov<"bg">(Q)(0, 0) = gyro_bias_walk * gyro_bias_walk * dt;
    L::cov<"ba">(Q).diagonal().setConstant(accel_bias_walk * accel_bias_walk * dt);
    return Q;
  }
};

/// 2-D GNSS position fix: z = p, noise R (set per epoch from the receiver's reported sigma).
struct PlanarPosition {
  using L = PlanarLayout;
  static constexpr int dim = 2;
  SquareMatrix<2> R = SquareMatrix<2>::Identity();

  Vector<2> predict(const Vector<L::size>& x, Matrix<2, L::size>* H) const {
    if (H) {
      H->setZero();
      L::cols<"p">(*H).setIdentity();
    }
    return L::get<"p">(x);
  }
  SquareMatrix<2> noise(const Vector<L::size>&) const { return R; }
};

/// UWB range from a tag at height `tag_height` above the planar position to an anchor given
/// in 3-D: z = sqrt(|p - a_xy|^2 + (h - a_z)^2).
struct PlanarRange {
  using L = PlanarLayout;
  static constexpr int dim = 1;
  Vector<3> anchor = Vector<3>::Zero();
  double tag_height = 1.0;
  double sigma = 0.1;

  template <class T>
  Vector<1, T> value(const Vector<L::size, T>& x) const {
    using std::sqrt;
    const T dx = x(L::offset<"p">()) - T(anchor(0)), dy = x(L::offset<"p">() + 1) - T(anchor(1));
    const double dz = tag_height - anchor(2);
    return Vector<1, T>(sqrt(dx * dx + dy * dy + T(dz * dz)));
  }

  Vector<1> predict(const Vector<L::size>& x, Matrix<1, L::size>* H) const {
    const Vector<2> d = L::get<"p">(x) - anchor.head<2>();
    const double dz = tag_height - anchor(2);
    const double r = std::sqrt(d.squaredNorm() + dz * dz);
    if (H) {
      H->setZero();
      // Undefined only exactly at the anchor; a zero row makes the update a no-op there.
      if (r > 0.0) L::cols<"p">(*H) = d.transpose() / r;
    }
    return Vector<1>(r);
  }
  SquareMatrix<1> noise(const Vector<L::size>&) const { return SquareMatrix<1>(sigma * sigma); }
  Problem check(const Vector<1>& z) const { return z(0) < 0.0 ? Problem::measurement_out_of_domain : Problem::none; }
};

/// Velocity in the body frame: z = R(psi)' v = (forward, lateral). With z = (wheel speed, 0)
/// it is the odometer plus the non-holonomic constraint of a car (no side slip).
struct PlanarBodyVelocity {
  using L = PlanarLayout;
  static constexpr int dim = 2;
  double forward_sigma = 0.1;  // [m/s]
  double lateral_sigma = 0.1;  // [m/s] how far the no-side-slip assumption is trusted

  Vector<2> predict(const Vector<L::size>& x, Matrix<2, L::size>* H) const {
    const double psi = L::get<"psi">(x)(0);
    const double c = std::cos(psi), s = std::sin(psi);
    const Vector<2> v = L::get<"v">(x);
    if (H) {
      H->setZero();
      Matrix<2, 2> Rt;
      Rt << c, s, -s, c;
      L::cols<"v">(*H) = Rt;
      L::cols<"psi">(*H) = Vector<2>(-s * v(0) + c * v(1), -c * v(0) - s * v(1));
    }
    return Vector<2>(c * v(0) + s * v(1), -s * v(0) + c * v(1));
  }
  SquareMatrix<2> noise(const Vector<L::size>&) const {
    return Vector<2>(forward_sigma * forward_sigma, lateral_sigma * lateral_sigma).asDiagonal();
  }
};

/// Lateral body velocity alone, z = -sin(psi) v_x + cos(psi) v_y: with z = 0 the
/// non-holonomic constraint of a car (no side slip) without an odometer.
struct PlanarLateralVelocity {
  using L = PlanarLayout;
  static constexpr int dim = 1;
  double sigma = 0.1;  // [m/s]

  Vector<1> predict(const Vector<L::size>& x, Matrix<1, L::size>* H) const {
    const double psi = L::get<"psi">(x)(0);
    const double c = std::cos(psi), s = std::sin(psi);
    const Vector<2> v = L::get<"v">(x);
    if (H) {
      H->setZero();
      (*H)(0, L::offset<"v">()) = -s;
      (*H)(0, L::offset<"v">() + 1) = c;
      (*H)(0, L::offset<"psi">()) = -c * v(0) - s * v(1);
    }
    return Vector<1>(-s * v(0) + c * v(1));
  }
  SquareMatrix<1> noise(const Vector<L::size>&) const { return SquareMatrix<1>(sigma * sigma); }
};

/// Any measurement with its noise covariance multiplied by `factor` (> 0): how one sub-model
/// weights a sensor differently from another (the region paper's "weighted" GNSS + UWB mode).
template <class Meas>
struct ScaledNoise {
  static constexpr int dim = Meas::dim;
  Meas inner;
  double factor = 1.0;

  template <class X, int N>
  Vector<dim> predict(const X& x, Matrix<dim, N>* H) const {
    return inner.predict(x, H);
  }
  template <class X>
  SquareMatrix<dim> noise(const X& x) const {
    return factor * inner.noise(x);
  }
  Problem check(const Vector<dim>& z) const {
    if constexpr (requires { { inner.check(z) } -> std::convertible_to<Problem>; })
      return inner.check(z);
    else
      return Problem::none;
  }
};

}  // namespace ctxfuse::models

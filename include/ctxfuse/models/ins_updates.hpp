// Measurement models of the geodetic INS (models/ins_nav.hpp), over any BlockState that has
// its blocks p (geodetic), v (NED), theta (body -> NED), bg, and optionally the augmented
// blocks "lever" (3, body frame) and "mount" (2: pitch, heading of the vehicle in the body
// frame). Each is used with a gate: ChiSquareGate (policies/gating.hpp, one-tailed on the NIS)
// for GNSS, and for the constraints too, so that a wrong static/moving decision is refused
// rather than forced in. The detectors that decide when a constraint applies (static
// detection, quasi-static magnetic field, dynamic alignment) are in models/ins_motion.hpp.
#pragma once

#include <cmath>

#include "ctxfuse/core/block_state.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/models/earth.hpp"
#include "ctxfuse/models/ins_nav.hpp"

namespace ctxfuse::models {

/// R for a geodetic position fix in the measurement's units (rad^2, rad^2, m^2) from a
/// covariance in metres north/east/down (the scene paper's eq. 21 for a diagonal one).
inline Eigen::Matrix3d geodetic_position_noise(const Eigen::Vector3d& llh, const Eigen::Matrix3d& cov_ned) {
  const Eigen::Matrix3d D = earth::ned_per_llh(llh(0), llh(2)).cwiseInverse().asDiagonal();
  return D * cov_ned * D;
}

/// A covariance given in east/north/up (messages::GnssFix::cov) in north/east/down axes.
inline Eigen::Matrix3d ned_from_enu_cov(const Eigen::Matrix3d& enu) {
  Eigen::Matrix3d T;
  T << 0, 1, 0, 1, 0, 0, 0, 0, -1;
  return T * enu * T.transpose();
}

/// GNSS antenna position z = (lat, lon, h) [rad, rad, m] = p [+] C l, l the lever arm from the
/// IMU to the antenna in the body frame.
template <class S>
struct GnssGeodeticPosition {
  using L = typename S::ErrorLayout;
  static constexpr int dim = 3;
  static constexpr auto jacobian_columns = column_pattern<L>({"p", "theta"});
  Eigen::Vector3d lever_arm = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // see geodetic_position_noise

  Vector<3> predict(const S& x, Matrix<3, L::size>* H) const {
    const Eigen::Vector3d& llh = x.template get<"p">();
    const Eigen::Matrix3d C = x.template get<"theta">().toRotationMatrix();
    const Eigen::Vector3d per = earth::ned_per_llh(llh(0), llh(2)).cwiseInverse();
    if (H) {
      H->setZero();
      L::template cols<"p">(*H) = per.asDiagonal();
      // d(C Exp(e) l)/de = -C [l]x, in radians and metres of the fix.
      L::template cols<"theta">(*H) = per.asDiagonal() * (-C * so3::skew(lever_arm));
    }
    return llh + per.cwiseProduct(C * lever_arm);
  }
  SquareMatrix<3> noise(const S&) const { return R; }
  Vector<3> residual(const Vector<3>& z, const Vector<3>& z_pred) const {
    Vector<3> y = z - z_pred;
    y(1) = std::remainder(y(1), 2.0 * 3.14159265358979323846);
    return y;
  }
};

/// GNSS antenna velocity z = v + C (w x l) [m/s NED], w = gyro - bg the body rate
/// (d(w x l)/dbg = [l]x).
template <class S>
struct GnssVelocity {
  using L = typename S::ErrorLayout;
  static constexpr int dim = 3;
  static constexpr auto jacobian_columns = column_pattern<L>({"v", "theta", "bg"});
  Eigen::Vector3d lever_arm = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();

  Vector<3> predict(const S& x, Matrix<3, L::size>* H) const {
    const Eigen::Matrix3d C = x.template get<"theta">().toRotationMatrix();
    const Eigen::Vector3d w = gyro - x.template get<"bg">();
    const Eigen::Vector3d wl = w.cross(lever_arm);
    if (H) {
      H->setZero();
      L::template cols<"v">(*H).setIdentity();
      L::template cols<"theta">(*H) = -C * so3::skew(wl);
      L::template cols<"bg">(*H) = C * so3::skew(lever_arm);
    }
    return x.template get<"v">() + C * wl;
  }
  SquareMatrix<3> noise(const S&) const { return R; }
};

/// ZUPT: the velocity is zero, z = 0 [m/s].
template <class S>
struct ZeroVelocity {
  using L = typename S::ErrorLayout;
  static constexpr int dim = 3;
  static constexpr auto jacobian_columns = column_pattern<L>({"v"});
  double sigma = 0.02;  // [m/s]
  Vector<3> predict(const S& x, Matrix<3, L::size>* H) const {
    if (H) {
      H->setZero();
      L::template cols<"v">(*H).setIdentity();
    }
    return x.template get<"v">();
  }
  SquareMatrix<3> noise(const S&) const { return SquareMatrix<3>::Identity() * sigma * sigma; }
};

/// A heading [rad]: z = heading(C). ZIHR holds the heading stored at the start of a static
/// period; the magnetometer gives the heading at a quasi-static epoch k0 plus the change the
/// magnetometer saw since (models/ins_motion.hpp). Residuals wrap to (-pi, pi].
template <class S>
struct Heading {
  using L = typename S::ErrorLayout;
  static constexpr int dim = 1;
  static constexpr auto jacobian_columns = column_pattern<L>({"theta"});
  double sigma = 0.01;  // [rad]
  Vector<1> predict(const S& x, Matrix<1, L::size>* H) const {
    const Eigen::Matrix3d C = x.template get<"theta">().toRotationMatrix();
    if (H) {
      H->setZero();
      L::template cols<"theta">(*H) = heading_jacobian(C);
    }
    return Vector<1>(heading_of(C));
  }
  SquareMatrix<1> noise(const S&) const { return SquareMatrix<1>(sigma * sigma); }
  Vector<1> residual(const Vector<1>& z, const Vector<1>& z_pred) const {
    return Vector<1>(PlanarAngleRetraction::wrap(z(0) - z_pred(0)));
  }
};

/// Velocity of the vehicle's reference point (rear-axle centre, at lever arm l from the IMU in
/// the body frame) in the vehicle frame (forward, right, down): u = C_vb (C' v + w x l), with
/// C_bv = Rz(heading_m) Ry(pitch_m) the vehicle's mounting in the body frame. The lever arm and
/// the mounting angles are the state's blocks "lever" and "mount" when it has them, these
/// members otherwise. Row 0 is the forward speed, rows 1-2 are what the non-holonomic
/// constraint holds at zero.
template <class S>
struct VehicleVelocity {
  using L = typename S::ErrorLayout;
  Eigen::Vector3d lever_arm = Eigen::Vector3d::Zero();
  Eigen::Vector2d mount = Eigen::Vector2d::Zero();  // pitch, heading [rad]
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();   // latest measured body rate [rad/s]

  Eigen::Vector3d evaluate(const S& x, Matrix<3, L::size>* H) const {
    Eigen::Vector3d l = lever_arm;
    Eigen::Vector2d m = mount;
    if constexpr (S::has("lever")) l = x.template get<"lever">();
    if constexpr (S::has("mount")) m = x.template get<"mount">();
    const Eigen::Matrix3d C = x.template get<"theta">().toRotationMatrix();
    const Eigen::Matrix3d Ry = Eigen::AngleAxisd(m(0), Eigen::Vector3d::UnitY()).toRotationMatrix();
    const Eigen::Matrix3d Rz = Eigen::AngleAxisd(m(1), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Matrix3d C_vb = Ry.transpose() * Rz.transpose();
    const Eigen::Vector3d w = gyro - x.template get<"bg">();
    const Eigen::Vector3d v_b = C.transpose() * x.template get<"v">();
    const Eigen::Vector3d u_b = v_b + w.cross(l);
    if (H) {
      H->setZero();
      L::template cols<"v">(*H) = C_vb * C.transpose();
      L::template cols<"theta">(*H) = C_vb * so3::skew(v_b);  // C_true' = Exp(-e) C'
      L::template cols<"bg">(*H) = C_vb * so3::skew(l);
      if constexpr (S::has("lever")) L::template cols<"lever">(*H) = C_vb * so3::skew(w);
      if constexpr (S::has("mount")) {
        const Eigen::Vector3d rz_u = Rz.transpose() * u_b;
        L::template cols<"mount">(*H).col(0) = -so3::skew(Eigen::Vector3d::UnitY()) * (Ry.transpose() * rz_u);
        L::template cols<"mount">(*H).col(1) = Ry.transpose() * (-so3::skew(Eigen::Vector3d::UnitZ()) * rz_u);
      }
    }
    return C_vb * u_b;
  }
};

/// Non-holonomic constraint: lateral and vertical velocity of the vehicle point are zero.
template <class S>
struct NonHolonomic {
  using L = typename S::ErrorLayout;
  static constexpr int dim = 2;
  VehicleVelocity<S> vehicle;
  double sigma = 0.1;  // [m/s]
  Vector<2> predict(const S& x, Matrix<2, L::size>* H) const {
    Matrix<3, L::size> J;
    const Eigen::Vector3d u = vehicle.evaluate(x, H ? &J : nullptr);
    if (H) *H = J.template bottomRows<2>();
    return u.tail<2>();
  }
  SquareMatrix<2> noise(const S&) const { return SquareMatrix<2>::Identity() * sigma * sigma; }
};

/// Non-holonomic constraint with a forward-speed pseudo-measurement (odometer or any external
/// predictor): z = (speed, 0, 0) in the vehicle frame. A state with a block "speed_scale" (1)
/// carries the speed source's scale error k (a wheel-radius error: measured = (1 + k) true), so
/// the predicted speed is (1 + k) u_0; without it k = 0. Unmodelled, k is an along-track drift
/// that no covariance accounts for (1 % is 5.8 m over 580 m of dead reckoning).
template <class S>
struct NonHolonomicWithSpeed {
  using L = typename S::ErrorLayout;
  static constexpr int dim = 3;
  VehicleVelocity<S> vehicle;
  double sigma_lateral = 0.1;  // [m/s]
  double sigma_speed = 0.1;    // [m/s]
  Vector<3> predict(const S& x, Matrix<3, L::size>* H) const {
    Vector<3> u = vehicle.evaluate(x, H);
    if constexpr (S::has("speed_scale")) {
      const double k = x.template get<"speed_scale">()(0);
      if (H) {
        H->row(0) *= 1.0 + k;
        L::template cols<"speed_scale">(*H)(0, 0) = u(0);
      }
      u(0) *= 1.0 + k;
    }
    return u;
  }
  SquareMatrix<3> noise(const S&) const {
    return Eigen::Vector3d(sigma_speed * sigma_speed, sigma_lateral * sigma_lateral, sigma_lateral * sigma_lateral)
        .asDiagonal();
  }
};

}  // namespace ctxfuse::models

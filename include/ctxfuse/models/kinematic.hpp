// Kinematic models over named layouts: constant velocity with white-noise acceleration, the
// same driven by a measured acceleration (IMU), a direct observation of one named block, and
// the range to a known point (UWB anchor).
//
// The prediction and range models also have a `value<T>` form templated on the scalar: the
// factor-graph smoother (filters/fixed_lag.hpp) evaluates residuals through it, and the tests
// pass ceres::Jet through it to check the analytic Jacobians against automatic ones, so the
// EKF, the smoother and Ceres all use the one function.
#pragma once

#include <cmath>

#include "ctxfuse/core/block_sparsity.hpp"
#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse::models {

/// Discrete noise of white acceleration with spectral density q [m^2/s^3] on blocks "p", "v"
/// (D each) of layout L: Q_pp = q dt^3/3, Q_pv = q dt^2/2, Q_vv = q dt; other blocks zero.
template <class L, int D>
SquareMatrix<L::size> white_acceleration_noise(double q, double dt) {
  SquareMatrix<L::size> Q = SquareMatrix<L::size>::Zero();
  L::template cov<"p">(Q).diagonal().setConstant(q * dt * dt * dt / 3.0);
  L::template cov<"p", "v">(Q).diagonal().setConstant(q * dt * dt / 2.0);
  L::template cov<"v", "p">(Q).diagonal().setConstant(q * dt * dt / 2.0);
  L::template cov<"v">(Q).diagonal().setConstant(q * dt);
  return Q;
}

/// Constant velocity in D dimensions over blocks "p" and "v" of layout L (other blocks are
/// held constant). Continuous white acceleration noise of spectral density q [m^2/s^3].
template <class L, int D = 3>
struct ConstantVelocity {
  static_assert(L::template size_of<"p">() == D && L::template size_of<"v">() == D);
  static constexpr int dim = L::size;
  using State = Vector<dim>;
  using Input = NoInput;
  static constexpr bool affine_in_state = true;  // F depends on dt only

  double accel_psd = 1.0;

  template <class T>
  Vector<dim, T> value(const Vector<dim, T>& x, const Input&, double dt) const {
    Vector<dim, T> out = x;
    L::template get<"p">(out) += T(dt) * L::template get<"v">(x);
    return out;
  }

  State predict(const State& x, const Input& u, double dt, SquareMatrix<dim>* F) const {
    if (F) {
      F->setIdentity();
      F->template block<D, D>(L::template offset<"p">(), L::template offset<"v">()).diagonal().setConstant(dt);
    }
    return value<double>(x, u, dt);
  }

  SquareMatrix<dim> noise(const State&, const Input&, double dt) const {
    return white_acceleration_noise<L, D>(accel_psd, dt);
  }
};

/// Position and velocity driven by a measured acceleration a (navigation frame, gravity
/// removed: an IMU's specific force rotated by a known attitude), held over the step:
///   p+ = p + v dt + a dt^2/2,  v+ = v + a dt.
/// The acceleration's white noise, density sigma_a [m/s^2/sqrt(Hz)], enters as white
/// acceleration noise of spectral density sigma_a^2 (plus what the caller adds for unmodelled
/// motion). Constant velocity is the case a = 0.
template <class L, int D = 3>
struct AccelerationDriven {
  static_assert(L::template size_of<"p">() == D && L::template size_of<"v">() == D);
  static constexpr int dim = L::size;
  using State = Vector<dim>;
  using Input = Vector<D>;
  static constexpr bool affine_in_state = true;  // F depends on dt only; a enters as an offset

  double accel_psd = 1.0;           // [m^2/s^3]
  double max_abs_accel = 200.0;     // [m/s^2] beyond this a sample is broken, not motion

  Problem check_input(const Input& a) const {
    return a.cwiseAbs().maxCoeff() > max_abs_accel ? Problem::input_magnitude : Problem::none;
  }

  template <class T>
  Vector<dim, T> value(const Vector<dim, T>& x, const Input& a, double dt) const {
    Vector<dim, T> out = x;
    const Vector<D, T> a_t = a.template cast<T>();
    L::template get<"p">(out) += T(dt) * L::template get<"v">(x) + T(0.5 * dt * dt) * a_t;
    L::template get<"v">(out) += T(dt) * a_t;
    return out;
  }

  State predict(const State& x, const Input& a, double dt, SquareMatrix<dim>* F) const {
    if (F) {
      F->setIdentity();
      F->template block<D, D>(L::template offset<"p">(), L::template offset<"v">()).diagonal().setConstant(dt);
    }
    return value<double>(x, a, dt);
  }

  SquareMatrix<dim> noise(const State&, const Input&, double dt) const {
    return white_acceleration_noise<L, D>(accel_psd, dt);
  }
};

/// z = block `Name` of the state + noise with covariance R.
template <class L, FixedString Name>
struct BlockObservation {
  static constexpr int dim = L::template size_of<Name>();
  static constexpr auto jacobian_columns = column_pattern<L>({Name.view()});
  SquareMatrix<dim> R = SquareMatrix<dim>::Identity();

  template <class T>
  Vector<dim, T> value(const Vector<L::size, T>& x) const {
    return L::template get<Name>(x);
  }
  Vector<dim> predict(const Vector<L::size>& x, Matrix<dim, L::size>* H) const {
    if (H) {
      H->setZero();
      L::template cols<Name>(*H).setIdentity();
    }
    return value<double>(x);
  }
  SquareMatrix<dim> noise(const Vector<L::size>&) const { return R; }
};

/// Range from block "p" (D elements) to a fixed point: z = |p - anchor| + noise.
template <class L, int D = 3>
struct RangeToPoint {
  static constexpr int dim = 1;
  static constexpr auto jacobian_columns = column_pattern<L>({std::string_view("p")});
  Vector<D> anchor = Vector<D>::Zero();
  double sigma = 0.1;

  template <class T>
  Vector<1, T> value(const Vector<L::size, T>& x) const {
    const Vector<D, T> d = L::template get<"p">(x) - anchor.template cast<T>();
    return Vector<1, T>(d.norm());
  }

  Vector<1> predict(const Vector<L::size>& x, Matrix<1, L::size>* H) const {
    const Vector<D> d = L::template get<"p">(x) - anchor;
    const double r = d.norm();
    if (H) {
      H->setZero();
      // The gradient is undefined at the anchor; a zero row makes the update a no-op there
      // rather than a NaN.
      if (r > 0.0) L::template cols<"p">(*H) = d.transpose() / r;
    }
    return Vector<1>(r);
  }
  SquareMatrix<1> noise(const Vector<L::size>&) const { return SquareMatrix<1>(sigma * sigma); }
  Problem check(const Vector<1>& z) const {
    return z(0) < 0.0 ? Problem::measurement_out_of_domain : Problem::none;
  }
};

}  // namespace ctxfuse::models

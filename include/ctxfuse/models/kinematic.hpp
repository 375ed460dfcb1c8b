// Kinematic models over named layouts: constant velocity with white-noise acceleration, a
// direct observation of one named block, and the range to a known point (UWB anchor).
#pragma once

#include <cmath>

#include "ctxfuse/core/block_sparsity.hpp"
#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse::models {

/// Constant velocity in D dimensions over blocks "p" and "v" of layout L (other blocks are
/// held constant). Continuous white acceleration noise of spectral density q [m^2/s^3]:
/// Q_pp = q dt^3/3, Q_pv = q dt^2/2, Q_vv = q dt.
template <class L, int D = 3>
struct ConstantVelocity {
  static_assert(L::template size_of<"p">() == D && L::template size_of<"v">() == D);
  static constexpr int dim = L::size;
  using State = Vector<dim>;
  using Input = NoInput;

  double accel_psd = 1.0;

  State predict(const State& x, const Input&, double dt, SquareMatrix<dim>* F) const {
    State out = x;
    L::template get<"p">(out) += dt * L::template get<"v">(x);
    if (F) {
      F->setIdentity();
      F->template block<D, D>(L::template offset<"p">(), L::template offset<"v">()).diagonal().setConstant(dt);
    }
    return out;
  }

  SquareMatrix<dim> noise(const State&, const Input&, double dt) const {
    SquareMatrix<dim> Q = SquareMatrix<dim>::Zero();
    L::template cov<"p">(Q).diagonal().setConstant(accel_psd * dt * dt * dt / 3.0);
    L::template cov<"p", "v">(Q).diagonal().setConstant(accel_psd * dt * dt / 2.0);
    L::template cov<"v", "p">(Q).diagonal().setConstant(accel_psd * dt * dt / 2.0);
    L::template cov<"v">(Q).diagonal().setConstant(accel_psd * dt);
    return Q;
  }
};

/// z = block `Name` of the state + noise with covariance R.
template <class L, FixedString Name>
struct BlockObservation {
  static constexpr int dim = L::template size_of<Name>();
  static constexpr auto jacobian_columns = column_pattern<L>({Name.view()});
  SquareMatrix<dim> R = SquareMatrix<dim>::Identity();

  Vector<dim> predict(const Vector<L::size>& x, Matrix<dim, L::size>* H) const {
    if (H) {
      H->setZero();
      L::template cols<Name>(*H).setIdentity();
    }
    return L::template get<Name>(x);
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

// The planar IMU model (planar.hpp) over an interval of IMU samples: the process model of an
// IMU factor between two states of a smoother whose states are not at the IMU's rate (one
// per UWB epoch). The input is the interval's samples, each with the time it is in force;
// the prediction chains PlanarImuModel's steps, F is the product of their transitions and Q
// their propagated sum:
//   x_n = f_n(... f_1(x_0)),  F = F_n ... F_1,  Q = sum_k (F_n ... F_{k+1}) Q_k (...)'.
// Unlike PlanarImuModel::predict, the heading is not wrapped: the motion factor's residual is
// x_{k+1} - f(x_k), plain subtraction, so the headings along a window must stay continuous.
#pragma once

#include <array>
#include <cmath>

#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"
#include "ctxfuse/models/interval_check.hpp"
#include "ctxfuse/models/planar.hpp"

namespace ctxfuse::models {

/// The IMU samples in force over an interval, in time order, at most C of them; `add` merges
/// a sample into the last one (dt-weighted mean) when full, so an interval longer than C
/// samples is still covered end to end, at a coarser step.
template <int C = 32>
struct PlanarImuInterval {
  static_assert(C >= 1);
  std::array<PlanarImu, C> samples{};
  std::array<double, C> dt{};
  int count = 0;

  void clear() { count = 0; }
  double duration() const {
    double s = 0.0;
    for (int k = 0; k < count; ++k) s += dt[static_cast<std::size_t>(k)];
    return s;
  }
  void add(const PlanarImu& u, double span) {
    if (count < C) {
      samples[static_cast<std::size_t>(count)] = u;
      dt[static_cast<std::size_t>(count++)] = span;
      return;
    }
    PlanarImu& last = samples[static_cast<std::size_t>(C - 1)];
    double& last_dt = dt[static_cast<std::size_t>(C - 1)];
    const double w = span / (last_dt + span);
    last.yaw_rate += w * (u.yaw_rate - last.yaw_rate);
    last.accel += w * (u.accel - last.accel);
    last_dt += span;
  }
  bool is_finite() const {
    for (int k = 0; k < count; ++k)
      if (!samples[static_cast<std::size_t>(k)].is_finite() || !std::isfinite(dt[static_cast<std::size_t>(k)])) return false;
    return true;
  }
  double max_abs() const {
    double m = 0.0;
    for (int k = 0; k < count; ++k) m = std::max(m, samples[static_cast<std::size_t>(k)].max_abs());
    return m;
  }
};

template <int C = 32>
struct PlanarImuIntervalModel {
  using L = PlanarLayout;
  using State = Vector<L::size>;
  using Input = PlanarImuInterval<C>;
  static constexpr int dim = L::size;

  PlanarImuModel step{};
  /// How far the samples' spans may sum from the step's dt (relative): an interval that does
  /// not cover the step is the caller's error, not motion.
  double duration_tolerance = 1e-6;

  Problem check_input(const Input& u) const {
    if (u.count < 1) return Problem::non_finite_input;
    for (int k = 0; k < u.count; ++k) {
      if (!(u.dt[static_cast<std::size_t>(k)] > 0.0)) return Problem::non_positive_dt;
      if (Problem p = step.check_input(u.samples[static_cast<std::size_t>(k)]); p != Problem::none) return p;
    }
    return Problem::none;
  }
  /// check_input, and that the spans cover dt.
  Problem check(const Input& u, double dt) const {
    if (Problem p = check_input(u); p != Problem::none) return p;
    return check_interval_duration(u.duration(), dt, duration_tolerance);
  }

  State predict(const State& x, const Input& u, double, SquareMatrix<dim>* F) const {
    State out = x;
    if (F) F->setIdentity();
    SquareMatrix<dim> Fk;
    for (int k = 0; k < u.count; ++k) {
      const double psi = out(L::offset<"psi">());
      out = step.predict(out, u.samples[static_cast<std::size_t>(k)], u.dt[static_cast<std::size_t>(k)], F ? &Fk : nullptr);
      out(L::offset<"psi">()) = psi + wrap_angle(out(L::offset<"psi">()) - psi);  // continuous heading
      if (F) *F = Fk * *F;
    }
    return out;
  }

  SquareMatrix<dim> noise(const State& x, const Input& u, double) const {
    SquareMatrix<dim> Q = SquareMatrix<dim>::Zero(), Fk;
    State xk = x;
    for (int k = 0; k < u.count; ++k) {
      const auto i = static_cast<std::size_t>(k);
      xk = step.predict(xk, u.samples[i], u.dt[i], &Fk);
      Q = Fk * Q * Fk.transpose() + step.noise(xk, u.samples[i], u.dt[i]);
    }
    return Q;
  }
};

}  // namespace ctxfuse::models

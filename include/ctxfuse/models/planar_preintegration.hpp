// Preintegrated IMU measurement of the planar IMU state (planar.hpp): the samples of an
// interval summed once into deltas in the frame of the interval's first heading, with their
// covariance and their Jacobians with respect to the biases, so that the IMU factor between
// two smoother states costs a few 2 x 2 products per linearisation instead of re-chaining the
// interval's samples (planar_interval.hpp) at every one.
//
// The planar form of on-manifold preintegration: the rotation is the heading, an angle, so
// R(psi_i + dpsi) = R(psi_i) R(dpsi) and PlanarImuModel's steps from a state x_i give exactly
//   psi_j = psi_i + dpsi,  v_j = v_i + R(psi_i) dv,  p_j = p_i + v_i T + R(psi_i) dp,
// with (dp, dv, dpsi) the same steps chained from the local origin (p = v = 0, psi = 0) at the
// state's biases. The deltas are formed once, at biases (bg0, ba0); for other biases they are
// corrected to first order, without re-integration:
//   dpsi(bg) = dpsi0 - T (bg - bg0)                            (exact),
//   dv(b) = dv0 + dv/dbg (bg - bg0) + dv/dba (ba - ba0),  dp likewise.
// The correction is exact in ba when bg = bg0; its error (remainder_bound) comes from the
// heading error T (bg - bg0) inside the rotations and is bounded by
//   |dv error| <= 1/2 dbg^2 sum_k dt_k t_k^2 |f_k - ba0| + |dbg| |dba| sum_k dt_k t_k,
// t_k the time of sample k from the interval's start (|R(a + h) - R(a) - R'(a) h| <= h^2 / 2,
// |R(h) - I| <= |h|), and dp's error by the same terms integrated once more.
//
// The covariance is the chained step noise of planar_interval.hpp, Q = F_n Q_{n-1} F_n' + Q_n,
// formed at heading 0 and rotated to the first state's heading at use: each step's F at
// heading psi_i + a is T F(a) T' with T = diag(R(psi_i), R(psi_i), 1, 1, I), and each step's
// noise is isotropic in the plane, so Q(psi_i) = T Q(0) T' exactly.
//
// PlanarPreintegratedModel is a process model whose input is the preintegrated measurement:
// the motion factor of a smoother, an EKF's prediction, and a Ceres cost (value<T>) use it
// alike. As in planar_interval.hpp the heading is not wrapped.
#pragma once

#include <algorithm>
#include <cmath>
#include <utility>

#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"
#include "ctxfuse/models/interval_check.hpp"
#include "ctxfuse/models/planar.hpp"

namespace ctxfuse::models {

/// The deltas of one interval at the biases (bg0, ba0), their bias Jacobians and covariance.
/// Made by reset() and add(); nothing is allocated.
class PlanarPreintegrated {
 public:
  using L = PlanarLayout;
  static constexpr int dim = L::size;

  /// Starts an empty interval at the biases (bg0, ba0), with m's noise densities. Non-finite
  /// biases are refused (non_finite_input) and leave the interval as it was.
  Problem reset(const PlanarImuModel& m, double bg0, const Vector<2>& ba0) {
    if (!std::isfinite(bg0) || !ba0.allFinite()) return Problem::non_finite_input;
    *this = PlanarPreintegrated{};
    model_ = m;
    bg0_ = bg0;
    ba0_ = ba0;
    return Problem::none;
  }

  /// Adds sample u in force over `span` seconds after the samples added so far. Refused, and
  /// nothing changed: a non-finite sample or span (non_finite_input, non_finite_dt), span <= 0
  /// (non_positive_dt), a sample beyond the model's magnitudes (input_magnitude).
  Problem add(const PlanarImu& u, double span) {
    if (!u.is_finite()) return Problem::non_finite_input;
    if (!std::isfinite(span)) return Problem::non_finite_dt;
    if (!(span > 0.0)) return Problem::non_positive_dt;
    if (Problem p = model_.check_input(u); p != Problem::none) return p;
    const double dt = span, t = duration_;
    const double c = std::cos(dpsi_), s = std::sin(dpsi_);
    Matrix<2, 2> R, dR;  // R(dpsi) and its derivative
    R << c, -s, s, c;
    dR << -s, -c, c, -s;
    const Vector<2> f = u.accel - ba0_;
    const Vector<2> a = R * f;
    const Vector<2> da_dpsi = dR * f;
    const double fn = f.norm();

    // Remainder sums (before the step's own velocity enters the position).
    sp2_ += dt * sv2_ + 0.5 * dt * dt * t * t * fn;
    sp1_ += dt * sv1_ + 0.5 * dt * dt * t;
    sv2_ += dt * t * t * fn;
    sv1_ += dt * t;

    // Bias Jacobians: d(dpsi)/dbg = -t before the step.
    dp_dbg_ += dt * dv_dbg_ - 0.5 * dt * dt * t * da_dpsi;
    dp_dba_ += dt * dv_dba_ - 0.5 * dt * dt * R;
    dv_dbg_ += -dt * t * da_dpsi;
    dv_dba_ += -dt * R;

    // Covariance: Q <- F Q F' + Q_step, F = I + E with E's few non-zero blocks (planar.hpp),
    // Q_step the model's own step noise (it depends on dt only).
    propagate_covariance(dt, 0.5 * dt * dt * da_dpsi, dt * da_dpsi, -0.5 * dt * dt * R, -dt * R);
    Q_ += model_.noise(Vector<dim>::Zero(), u, dt);

    // Deltas.
    dp_ += dv_ * dt + 0.5 * dt * dt * a;
    dv_ += dt * a;
    dpsi_ += (u.yaw_rate - bg0_) * dt;
    duration_ += dt;
    ++count_;
    return Problem::none;
  }

  int count() const { return count_; }
  double duration() const { return duration_; }
  double bg0() const { return bg0_; }
  const Vector<2>& ba0() const { return ba0_; }
  /// The deltas at (bg0, ba0), in the frame of the interval's first heading.
  double dpsi() const { return dpsi_; }
  const Vector<2>& dv() const { return dv_; }
  const Vector<2>& dp() const { return dp_; }
  const Vector<2>& dv_dbg() const { return dv_dbg_; }
  const Vector<2>& dp_dbg() const { return dp_dbg_; }
  const Matrix<2, 2>& dv_dba() const { return dv_dba_; }
  const Matrix<2, 2>& dp_dba() const { return dp_dba_; }
  /// The covariance of x_j - f(x_i) at heading 0 (PlanarLayout order).
  const SquareMatrix<dim>& covariance_at_zero_heading() const { return Q_; }

  /// Bounds on the error of the first-order bias correction at biases (bg0 + dbg, ba0 + dba):
  /// .first for the velocity delta, .second for the position delta [m/s, m] (Euclidean norms).
  std::pair<double, double> remainder_bound(double dbg, const Vector<2>& dba) const {
    const double g = std::abs(dbg), a = dba.norm();
    return {0.5 * g * g * sv2_ + g * a * sv1_, 0.5 * g * g * sp2_ + g * a * sp1_};
  }

  bool is_finite() const {
    return std::isfinite(dpsi_) && dv_.allFinite() && dp_.allFinite() && std::isfinite(duration_) && Q_.allFinite() &&
           dv_dbg_.allFinite() && dp_dbg_.allFinite() && dv_dba_.allFinite() && dp_dba_.allFinite();
  }
  /// The largest delta, for the filters' input-magnitude check.
  double max_abs() const {
    return std::max({std::abs(dpsi_), dv_.cwiseAbs().maxCoeff(), dp_.cwiseAbs().maxCoeff(), duration_});
  }

 private:
  static constexpr int P = L::offset<"p">(), V = L::offset<"v">(), PSI = L::offset<"psi">(), BG = L::offset<"bg">(),
                       BA = L::offset<"ba">();

  // Q <- F Q F' for F = I except: F(p, v) = dt I, F(p, psi) = cp, F(v, psi) = cv,
  // F(p, ba) = Bp, F(v, ba) = Bv, F(psi, bg) = -dt: rows first (old rows on the right), then
  // the same on columns.
  void propagate_covariance(double dt, const Vector<2>& cp, const Vector<2>& cv, const Matrix<2, 2>& Bp,
                            const Matrix<2, 2>& Bv) {
    Q_.middleRows<2>(P) += dt * Q_.middleRows<2>(V) + cp * Q_.row(PSI) + Bp * Q_.middleRows<2>(BA);
    Q_.middleRows<2>(V) += cv * Q_.row(PSI) + Bv * Q_.middleRows<2>(BA);
    Q_.row(PSI) -= dt * Q_.row(BG);
    Q_.middleCols<2>(P) += dt * Q_.middleCols<2>(V) + Q_.col(PSI) * cp.transpose() + Q_.middleCols<2>(BA) * Bp.transpose();
    Q_.middleCols<2>(V) += Q_.col(PSI) * cv.transpose() + Q_.middleCols<2>(BA) * Bv.transpose();
    Q_.col(PSI) -= dt * Q_.col(BG);
  }

  PlanarImuModel model_{};
  double bg0_ = 0.0;
  Vector<2> ba0_ = Vector<2>::Zero();
  double duration_ = 0.0;
  int count_ = 0;
  double dpsi_ = 0.0;
  Vector<2> dv_ = Vector<2>::Zero(), dp_ = Vector<2>::Zero();
  Vector<2> dv_dbg_ = Vector<2>::Zero(), dp_dbg_ = Vector<2>::Zero();
  Matrix<2, 2> dv_dba_ = Matrix<2, 2>::Zero(), dp_dba_ = Matrix<2, 2>::Zero();
  double sv1_ = 0.0, sv2_ = 0.0, sp1_ = 0.0, sp2_ = 0.0;  // remainder_bound's sums
  SquareMatrix<dim> Q_ = SquareMatrix<dim>::Zero();
};

/// The planar IMU state's process model over one preintegrated interval.
struct PlanarPreintegratedModel : PreintegratedIntervalCheck {
  using L = PlanarLayout;
  using State = Vector<L::size>;
  using Input = PlanarPreintegrated;
  static constexpr int dim = L::size;

  template <class T>
  Vector<dim, T> value(const Vector<dim, T>& x, const Input& u, double /*dt*/) const {
    using std::cos, std::sin;
    const T psi = x(L::offset<"psi">());
    const T c = cos(psi), s = sin(psi);
    const T dbg = x(L::offset<"bg">()) - T(u.bg0());
    const Vector<2, T> dba = L::get<"ba">(x) - u.ba0().template cast<T>();
    const Vector<2, T> dv = u.dv().template cast<T>() + u.dv_dbg().template cast<T>() * dbg + u.dv_dba().template cast<T>() * dba;
    const Vector<2, T> dp = u.dp().template cast<T>() + u.dp_dbg().template cast<T>() * dbg + u.dp_dba().template cast<T>() * dba;
    Vector<dim, T> out = x;
    const Vector<2, T> v = L::get<"v">(x);
    L::get<"p">(out) += T(u.duration()) * v + Vector<2, T>(c * dp(0) - s * dp(1), s * dp(0) + c * dp(1));
    L::get<"v">(out) += Vector<2, T>(c * dv(0) - s * dv(1), s * dv(0) + c * dv(1));
    out(L::offset<"psi">()) = psi + T(u.dpsi()) - T(u.duration()) * dbg;
    return out;
  }

  State predict(const State& x, const Input& u, double dt, SquareMatrix<dim>* F) const {
    if (F) {
      const double psi = x(L::offset<"psi">());
      const double c = std::cos(psi), s = std::sin(psi);
      Matrix<2, 2> R, dR;
      R << c, -s, s, c;
      dR << -s, -c, c, -s;
      const double dbg = x(L::offset<"bg">()) - u.bg0();
      const Vector<2> dba = L::get<"ba">(x) - u.ba0();
      const Vector<2> dv = u.dv() + u.dv_dbg() * dbg + u.dv_dba() * dba;
      const Vector<2> dp = u.dp() + u.dp_dbg() * dbg + u.dp_dba() * dba;
      F->setIdentity();
      L::cov<"p", "v">(*F).diagonal().setConstant(u.duration());
      L::cov<"p", "psi">(*F) = dR * dp;
      L::cov<"p", "bg">(*F) = R * u.dp_dbg();
      L::cov<"p", "ba">(*F) = R * u.dp_dba();
      L::cov<"v", "psi">(*F) = dR * dv;
      L::cov<"v", "bg">(*F) = R * u.dv_dbg();
      L::cov<"v", "ba">(*F) = R * u.dv_dba();
      L::cov<"psi", "bg">(*F)(0, 0) = -u.duration();
    }
    return value<double>(x, u, dt);
  }

  /// The interval's covariance rotated to x's heading: T Q(0) T', T = diag(R, R, 1, 1, I).
  SquareMatrix<dim> noise(const State& x, const Input& u, double) const {
    const double psi = x(L::offset<"psi">());
    const double c = std::cos(psi), s = std::sin(psi);
    SquareMatrix<dim> T = SquareMatrix<dim>::Identity();
    L::cov<"p">(T) << c, -s, s, c;
    L::cov<"v">(T) << c, -s, s, c;
    return T * u.covariance_at_zero_heading() * T.transpose();
  }
};

}  // namespace ctxfuse::models

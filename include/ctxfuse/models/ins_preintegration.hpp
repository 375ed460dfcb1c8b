// Preintegrated IMU measurement of the 3-D strapdown INS (ins.hpp, Ins15Model): the samples of
// an interval summed once into deltas of rotation, velocity and position in the body frame of
// the interval's first state, with their covariance and their Jacobians with respect to the
// gyro and accelerometer biases, so that an IMU factor between two smoother states costs a
// few 3 x 3 products per linearisation instead of re-chaining the interval's samples.
//
// The on-manifold form (Forster et al., "On-Manifold Preintegration for Real-Time
// Visual-Inertial Odometry", IEEE T-RO 2017). Ins15Model's steps from a state x_i, with
// constant gravity g and biases (bg0, ba0) held over the interval, give exactly
//   R_j = R_i dR,   v_j = v_i + g T + R_i dv,   p_j = p_i + v_i T + g T^2 / 2 + R_i dp,
// with (dp, dv, dR) the same steps chained from the local origin (p = v = 0, R = I, no
// gravity): the deltas do not depend on the state, and are formed once. For other biases
// (bg0 + dbg, ba0 + dba) they are corrected to first order, without re-integration:
//   dR(bg) = dR0 Exp(JR dbg),   dv(b) = dv0 + Jvg dbg + Jva dba,   dp likewise,
// with the Jacobians chained per sample (a = f - ba0 the sample's specific force, dR_k the
// delta before sample k, E_k = Exp((w - bg0) dt), Jr_k its right Jacobian):
//   JR <- E_k' JR - Jr_k dt,      Jvg <- Jvg - dR_k [a]x JR dt,      Jva <- Jva - dR_k dt,
//   Jpg <- Jpg + Jvg dt - dR_k [a]x JR dt^2 / 2,   Jpa <- Jpa + Jva dt - dR_k dt^2 / 2
// (old JR, Jvg, Jva on the right). The correction is exact in ba alone; its error is second
// order in the bias offsets (tests/factors/ins_preintegration_test.cpp measures it against
// re-integration; no closed-form bound is derived here for the 3-D rotation).
//
// The covariance is Ins15Model's chained step noise, Q <- F Q F' + Q_k over all 15 error
// states (the bias noise and its coupling into p, v and theta included), formed in the first
// state's body frame: Ins15Model's F at attitude R_i dR_k is T F_k T' with T = diag(R_i, R_i,
// I, I, I) and F_k its F at attitude dR_k, and its Q_k is isotropic in p and v, so the chained
// covariance from x_i is T Q T' exactly.
//
// InsPreintegratedModel is a process model whose input is the preintegrated measurement, on
// a plain 15-vector state (p, v, the attitude's rotation vector, bg, ba: Ins15Layout with its
// "theta" block holding Log(R) of body -> navigation) with its own difference (the attitude
// block as Log(Exp(b)' Exp(a)), the right-perturbation error of Ins15Model): the motion factor
// of a fixed-lag smoother, and a Ceres cost through value<T>, use it alike. With biases that
// are Gauss-Markov processes of finite tau, the factor holds the interval's first biases over
// the interval (Ins15Model decays them per sample: a gap of about |b| T^2 / (2 tau) in the
// integrated rate or force) and decays the bias states by exp(-T / tau) over it, as the chain.
#pragma once

#include <algorithm>
#include <cmath>

#include "ctxfuse/core/so3.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"
#include "ctxfuse/models/interval_check.hpp"
#include "ctxfuse/models/ins.hpp"

namespace ctxfuse::models {

/// The deltas of one interval at the biases (bg0, ba0), their bias Jacobians and covariance.
/// Made by reset() and add(); nothing is allocated.
class InsPreintegrated {
 public:
  using L = Ins15Layout;
  static constexpr int dim = L::size;

  /// Starts an empty interval at the biases (bg0, ba0) with m's gravity, noise densities and
  /// sample limits. Non-finite biases are refused (non_finite_input), the interval unchanged.
  Problem reset(const Ins15Model& m, const Eigen::Vector3d& bg0, const Eigen::Vector3d& ba0) {
    if (!bg0.allFinite() || !ba0.allFinite() || !m.gravity.allFinite()) return Problem::non_finite_input;
    *this = InsPreintegrated{};
    model_ = m;
    bg0_ = bg0;
    ba0_ = ba0;
    return Problem::none;
  }

  /// Adds sample u in force over `span` seconds after the samples added so far. Refused, and
  /// nothing changed: a non-finite sample or span (non_finite_input, non_finite_dt), span <= 0
  /// (non_positive_dt), increments or rates beyond the model's limits (Ins15Model::check_input).
  Problem add(const ImuSample& u, double span) {
    if (!u.gyro.allFinite() || !u.accel.allFinite()) return Problem::non_finite_input;
    if (!std::isfinite(span)) return Problem::non_finite_dt;
    if (!(span > 0.0)) return Problem::non_positive_dt;
    if (Problem p = model_.check_input(u); p != Problem::none) return p;
    const double dt = span;
    const Eigen::Vector3d w = u.gyro - bg0_, a = u.accel - ba0_;
    Eigen::Quaterniond q_step;
    Eigen::Matrix3d Jr_step;
    so3::exp_quat_and_right_jacobian(Eigen::Vector3d(w * dt), q_step, Jr_step);
    const Eigen::Matrix3d Et = q_step.toRotationMatrix().transpose();
    const Eigen::Matrix3d R = dR_;
    const Eigen::Matrix3d Ra = R * so3::skew(a);

    // Bias Jacobians, each from the old values of those after it.
    const Eigen::Matrix3d RaJ = Ra * JRg_;
    Jpg_ += dt * Jvg_ - 0.5 * dt * dt * RaJ;
    Jpa_ += dt * Jva_ - 0.5 * dt * dt * R;
    Jvg_ -= dt * RaJ;
    Jva_ -= dt * R;
    JRg_ = Et * JRg_ - dt * Jr_step;

    // Covariance: Q <- F Q F' + Q_k with Ins15Model's F at attitude dR_k.
    propagate_covariance(dt, -0.5 * dt * dt * Ra, -0.5 * dt * dt * R, -dt * Ra, -dt * R, Et, -dt * Jr_step,
                         model_.gyro_bias.decay(dt), model_.accel_bias.decay(dt));
    Q_ += model_.noise(InsState{}, u, dt);

    // Deltas.
    const Eigen::Vector3d acc = R * a;
    dp_ += dt * dv_ + 0.5 * dt * dt * acc;
    dv_ += dt * acc;
    dq_ = (dq_ * q_step).normalized();
    dR_ = dq_.toRotationMatrix();
    duration_ += dt;
    ++count_;
    return Problem::none;
  }

  int count() const { return count_; }
  double duration() const { return duration_; }
  const Eigen::Vector3d& bg0() const { return bg0_; }
  const Eigen::Vector3d& ba0() const { return ba0_; }
  const Eigen::Vector3d& gravity() const { return model_.gravity; }
  /// The bias states' decay over the interval (1 for random walks).
  double gyro_bias_decay() const { return model_.gyro_bias.decay(duration_); }
  double accel_bias_decay() const { return model_.accel_bias.decay(duration_); }
  /// The deltas at (bg0, ba0), in the body frame of the interval's first state.
  const Eigen::Quaterniond& dq() const { return dq_; }
  const Eigen::Matrix3d& dR() const { return dR_; }
  const Eigen::Vector3d& dv() const { return dv_; }
  const Eigen::Vector3d& dp() const { return dp_; }
  const Eigen::Matrix3d& dR_dbg() const { return JRg_; }
  const Eigen::Matrix3d& dv_dbg() const { return Jvg_; }
  const Eigen::Matrix3d& dv_dba() const { return Jva_; }
  const Eigen::Matrix3d& dp_dbg() const { return Jpg_; }
  const Eigen::Matrix3d& dp_dba() const { return Jpa_; }
  /// The covariance of the chained errors (Ins15Layout order) in the first state's body frame.
  const SquareMatrix<dim>& covariance_in_first_frame() const { return Q_; }

  bool is_finite() const {
    return dq_.coeffs().allFinite() && dv_.allFinite() && dp_.allFinite() && std::isfinite(duration_) && Q_.allFinite() &&
           JRg_.allFinite() && Jvg_.allFinite() && Jva_.allFinite() && Jpg_.allFinite() && Jpa_.allFinite();
  }
  /// The largest delta, for the filters' input-magnitude check.
  double max_abs() const { return std::max({dv_.cwiseAbs().maxCoeff(), dp_.cwiseAbs().maxCoeff(), duration_}); }

 private:
  static constexpr int P = L::offset<"p">(), V = L::offset<"v">(), TH = L::offset<"theta">(), BG = L::offset<"bg">(),
                       BA = L::offset<"ba">();

  // Q <- F Q F' for Ins15Model's F: I except F(p, v) = dt I, F(p, theta) = Cp, F(p, ba) = Bp,
  // F(v, theta) = Cv, F(v, ba) = Bv, F(theta, theta) = Et, F(theta, bg) = G, F(bg, bg) = kg I,
  // F(ba, ba) = ka I. Rows first (each from the old rows below it), then the same on columns.
  void propagate_covariance(double dt, const Eigen::Matrix3d& Cp, const Eigen::Matrix3d& Bp, const Eigen::Matrix3d& Cv,
                            const Eigen::Matrix3d& Bv, const Eigen::Matrix3d& Et, const Eigen::Matrix3d& G, double kg,
                            double ka) {
    Q_.middleRows<3>(P) += dt * Q_.middleRows<3>(V) + Cp * Q_.middleRows<3>(TH) + Bp * Q_.middleRows<3>(BA);
    Q_.middleRows<3>(V) += Cv * Q_.middleRows<3>(TH) + Bv * Q_.middleRows<3>(BA);
    const Matrix<3, dim> rows = Et * Q_.middleRows<3>(TH) + G * Q_.middleRows<3>(BG);
    Q_.middleRows<3>(TH) = rows;
    Q_.middleRows<3>(BG) *= kg;
    Q_.middleRows<3>(BA) *= ka;
    Q_.middleCols<3>(P) += dt * Q_.middleCols<3>(V) + Q_.middleCols<3>(TH) * Cp.transpose() + Q_.middleCols<3>(BA) * Bp.transpose();
    Q_.middleCols<3>(V) += Q_.middleCols<3>(TH) * Cv.transpose() + Q_.middleCols<3>(BA) * Bv.transpose();
    const Matrix<dim, 3> cols = Q_.middleCols<3>(TH) * Et.transpose() + Q_.middleCols<3>(BG) * G.transpose();
    Q_.middleCols<3>(TH) = cols;
    Q_.middleCols<3>(BG) *= kg;
    Q_.middleCols<3>(BA) *= ka;
  }

  Ins15Model model_{};
  Eigen::Vector3d bg0_ = Eigen::Vector3d::Zero(), ba0_ = Eigen::Vector3d::Zero();
  double duration_ = 0.0;
  int count_ = 0;
  Eigen::Quaterniond dq_ = Eigen::Quaterniond::Identity();
  Eigen::Matrix3d dR_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d dv_ = Eigen::Vector3d::Zero(), dp_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d JRg_ = Eigen::Matrix3d::Zero(), Jvg_ = Eigen::Matrix3d::Zero(), Jva_ = Eigen::Matrix3d::Zero(),
                  Jpg_ = Eigen::Matrix3d::Zero(), Jpa_ = Eigen::Matrix3d::Zero();
  SquareMatrix<dim> Q_ = SquareMatrix<dim>::Zero();
};

/// The 3-D INS state's process model over one preintegrated interval, on the vector state
/// (p, v, Log(R), bg, ba) in Ins15Layout order.
struct InsPreintegratedModel : PreintegratedIntervalCheck {
  using L = Ins15Layout;
  using State = Vector<L::size>;
  using Input = InsPreintegrated;
  static constexpr int dim = L::size;

  template <class T>
  Vector<dim, T> value(const Vector<dim, T>& x, const Input& u, double /*dt*/) const {
    const Vector<3, T> dbg = L::get<"bg">(x) - u.bg0().template cast<T>();
    const Vector<3, T> dba = L::get<"ba">(x) - u.ba0().template cast<T>();
    const Vector<3, T> dv = u.dv().template cast<T>() + u.dv_dbg().template cast<T>() * dbg + u.dv_dba().template cast<T>() * dba;
    const Vector<3, T> dp = u.dp().template cast<T>() + u.dp_dbg().template cast<T>() * dbg + u.dp_dba().template cast<T>() * dba;
    const Eigen::Quaternion<T> q_i = so3::exp_quat(Vector<3, T>(L::get<"theta">(x)));
    const Eigen::Quaternion<T> dq = u.dq().template cast<T>() * so3::exp_quat(Vector<3, T>(u.dR_dbg().template cast<T>() * dbg));
    const so3::Mat3<T> R = q_i.toRotationMatrix();
    const T dur = T(u.duration());
    const Vector<3, T> g = u.gravity().template cast<T>();
    Vector<dim, T> out;
    const Vector<3, T> v = L::get<"v">(x);
    L::get<"p">(out) = L::get<"p">(x) + dur * v + T(0.5) * dur * dur * g + R * dp;
    L::get<"v">(out) = v + dur * g + R * dv;
    L::get<"theta">(out) = so3::log(Eigen::Quaternion<T>(q_i * dq));
    L::get<"bg">(out) = T(u.gyro_bias_decay()) * L::get<"bg">(x);
    L::get<"ba">(out) = T(u.accel_bias_decay()) * L::get<"ba">(x);
    return out;
  }

  State predict(const State& x, const Input& u, double dt, SquareMatrix<dim>* F) const {
    const State out = value<double>(x, u, dt);
    if (F) {
      const Eigen::Vector3d phi = L::get<"theta">(x);
      const Eigen::Vector3d dbg = L::get<"bg">(x) - u.bg0(), dba = L::get<"ba">(x) - u.ba0();
      const Eigen::Vector3d rho = u.dR_dbg() * dbg;
      const Eigen::Vector3d dv = u.dv() + u.dv_dbg() * dbg + u.dv_dba() * dba;
      const Eigen::Vector3d dp = u.dp() + u.dp_dbg() * dbg + u.dp_dba() * dba;
      Eigen::Quaterniond q_i, q_rho;
      Eigen::Matrix3d Jr_i, Jr_rho;
      so3::exp_quat_and_right_jacobian(phi, q_i, Jr_i);
      so3::exp_quat_and_right_jacobian(rho, q_rho, Jr_rho);
      const Eigen::Matrix3d R = q_i.toRotationMatrix();
      const Eigen::Matrix3d dRc = (u.dq() * q_rho).toRotationMatrix();
      const Eigen::Matrix3d Jinv_j = so3::right_jacobian_inverse(Eigen::Vector3d(L::get<"theta">(out)));
      F->setZero();
      F->diagonal().setOnes();
      L::cov<"p", "v">(*F).diagonal().setConstant(u.duration());
      // R(phi + d) = R Exp(Jr(phi) d): d(R y)/d(phi) = -R [y]x Jr(phi).
      L::cov<"p", "theta">(*F) = -R * so3::skew(dp) * Jr_i;
      L::cov<"p", "bg">(*F) = R * u.dp_dbg();
      L::cov<"p", "ba">(*F) = R * u.dp_dba();
      L::cov<"v", "theta">(*F) = -R * so3::skew(dv) * Jr_i;
      L::cov<"v", "bg">(*F) = R * u.dv_dbg();
      L::cov<"v", "ba">(*F) = R * u.dv_dba();
      // Log(R Exp(Jr_i d) dRc) = phi_j + Jr^-1(phi_j) dRc' Jr_i d; the bias enters through
      // Exp(rho + JR e) = Exp(rho) Exp(Jr(rho) JR e).
      L::cov<"theta", "theta">(*F) = Jinv_j * dRc.transpose() * Jr_i;
      L::cov<"theta", "bg">(*F) = Jinv_j * Jr_rho * u.dR_dbg();
      L::cov<"bg", "bg">(*F).diagonal().setConstant(u.gyro_bias_decay());
      L::cov<"ba", "ba">(*F).diagonal().setConstant(u.accel_bias_decay());
    }
    return out;
  }

  /// The interval's covariance in the difference's coordinates at x: p and v rotated to the
  /// navigation frame, T Q T' with T = diag(R, R, I, I, I); the attitude block is already the
  /// right-perturbation error of the state at the interval's end.
  SquareMatrix<dim> noise(const State& x, const Input& u, double) const {
    const Eigen::Matrix3d R = so3::exp(Eigen::Vector3d(L::get<"theta">(x)));
    SquareMatrix<dim> T = SquareMatrix<dim>::Identity();
    L::cov<"p">(T) = R;
    L::cov<"v">(T) = R;
    return T * u.covariance_in_first_frame() * T.transpose();
  }

  /// a [-] b: plain subtraction except the attitude, Log(Exp(b)' Exp(a)).
  template <class T>
  Vector<dim, T> difference(const Vector<dim, T>& a, const Vector<dim, T>& b) const {
    Vector<dim, T> d = a - b;
    const Eigen::Quaternion<T> qa = so3::exp_quat(Vector<3, T>(L::get<"theta">(a)));
    const Eigen::Quaternion<T> qb = so3::exp_quat(Vector<3, T>(L::get<"theta">(b)));
    L::get<"theta">(d) = so3::log(Eigen::Quaternion<T>(qb.conjugate() * qa));
    return d;
  }
  /// The same with its Jacobians: with e = Log(Exp(b)' Exp(a)), d e/d a = Jr^-1(e) Jr(a) and
  /// d e/d b = -Jr^-1(-e) Jr(b) on the attitude blocks (Jr^-1(-e) is the left Jacobian's inverse).
  Vector<dim> difference(const Vector<dim>& a, const Vector<dim>& b, SquareMatrix<dim>* Ja, SquareMatrix<dim>* Jb) const {
    const Vector<dim> d = difference<double>(a, b);
    const Eigen::Vector3d e = L::get<"theta">(d);
    if (Ja) {
      Ja->setIdentity();
      L::cov<"theta">(*Ja) = so3::right_jacobian_inverse(e) * so3::right_jacobian(Eigen::Vector3d(L::get<"theta">(a)));
    }
    if (Jb) {
      *Jb = -SquareMatrix<dim>::Identity();
      L::cov<"theta">(*Jb) = -so3::right_jacobian_inverse(Eigen::Vector3d(-e)) * so3::right_jacobian(Eigen::Vector3d(L::get<"theta">(b)));
    }
    return d;
  }
};

}  // namespace ctxfuse::models

#pragma once
// The three variants of the zero-overhead comparison (see zero_overhead.cpp).
// One predict + update of the same 15-state ESKF (strapdown INS, 3-D position fix) written
// three ways in one binary:
//   ZeroOverhead/Engine       ctxfuse::Eskf<Ins15Model> with GnssPosition (all checks on)
//   ZeroOverhead/HandWritten  the same equations by hand with fixed-size Eigen and no input
//                             checks, exploiting by hand the block structure of F, H and G
//                             that the engine's models declare (what an expert writes)
//   ZeroOverhead/Dynamic      the same equations with dynamic-size Eigen (MatrixXd), dense
//                             F, H and G (what a runtime-sized filter does)
// All use the expanded Joseph form (core/numerics.hpp) and compute the NIS a gate would test.
// All three run the same input sequence; before timing, each is run for a few hundred steps
// and their states are compared, so a faster variant cannot be a wrong one.
#include <Eigen/Dense>
#include <array>
#include <cmath>

#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/models/ins.hpp"

// Keeps a value alive without the benchmark library (the step counter uses this file too).
#ifndef CTXFUSE_KEEP
#define CTXFUSE_KEEP(x) benchmark::DoNotOptimize(x)
#endif

namespace zero_overhead {
using namespace ctxfuse;
using models::ImuSample;
using models::InsState;

constexpr double kDt = 0.01;

// A short, repeating excitation so that no variant sees constant inputs.
struct Inputs {
  std::array<ImuSample, 64> imu;
  std::array<Eigen::Vector3d, 64> fix;
  Inputs() {
    for (int i = 0; i < 64; ++i) {
      imu[i].gyro = {0.01 * std::sin(0.3 * i), -0.02 * std::cos(0.2 * i), 0.1 + 0.05 * std::sin(0.1 * i)};
      imu[i].accel = {0.3 * std::cos(0.15 * i), 0.1 * std::sin(0.25 * i), 9.80665 + 0.05 * std::sin(0.4 * i)};
      fix[i] = {0.02 * i, -0.01 * i, 0.05 * std::sin(0.5 * i)};
    }
  }
};
inline const Inputs& inputs() {
  static const Inputs in;
  return in;
}

inline models::Ins15Model make_model() {
  models::Ins15Model m;
  m.gyro_noise_density = 2e-3;
  m.accel_noise_density = 2e-2;
  m.gyro_bias = {2e-5, 300.0};
  m.accel_bias = {3e-4, 300.0};
  return m;
}

inline eskf::Belief<models::Ins15Model> initial_belief() {
  eskf::Belief<models::Ins15Model> b;
  b.cov = SquareMatrix<15>::Identity() * 0.01;
  b.cov.topLeftCorner<3, 3>() *= 100.0;
  return b;
}

const SquareMatrix<3> kR = SquareMatrix<3>::Identity() * 0.04;
const Eigen::Vector3d kLeverArm(0.3, -0.1, 1.2);

// ---------------------------------------------------------------- engine
struct EngineFilter {
  models::GnssPosition<> gnss{kLeverArm, kR};
  Eskf<models::Ins15Model> filter{make_model(), initial_belief()};
  void step(int i) {
    CTXFUSE_KEEP(filter.predict(inputs().imu[i & 63], kDt));
    CTXFUSE_KEEP(filter.update(gnss, inputs().fix[i & 63]));
  }
  const InsState& state() const { return filter.nominal(); }
  const SquareMatrix<15>& cov() const { return filter.belief().cov; }
};

// ---------------------------------------------------------------- by hand, fixed size
struct HandWrittenFilter {
  using Mat15 = Eigen::Matrix<double, 15, 15>;
  using Vec15 = Eigen::Matrix<double, 15, 1>;
  models::Ins15Model m = make_model();
  InsState x = initial_belief().nominal;
  Mat15 P = initial_belief().cov;

  void step(int i) {
    const ImuSample& u = inputs().imu[i & 63];
    // Propagation.
    const Eigen::Vector3d w = u.gyro - x.bg, a = u.accel - x.ba;
    const Eigen::Matrix3d C = x.q.toRotationMatrix();
    const Eigen::Vector3d acc = C * a + m.gravity;
    const Eigen::Vector3d wdt = w * kDt;
    const double kg = m.gyro_bias.decay(kDt), ka = m.accel_bias.decay(kDt);
    Mat15 F = Mat15::Identity();
    const Eigen::Matrix3d Cax = C * so3::skew(a);
    F.block<3, 3>(0, 3).diagonal().setConstant(kDt);
    F.block<3, 3>(0, 6) = -0.5 * kDt * kDt * Cax;
    F.block<3, 3>(0, 12) = -0.5 * kDt * kDt * C;
    F.block<3, 3>(3, 6) = -kDt * Cax;
    F.block<3, 3>(3, 12) = -kDt * C;
    F.block<3, 3>(6, 6) = so3::exp(wdt).transpose();
    F.block<3, 3>(6, 9) = -kDt * so3::right_jacobian(wdt);
    F.block<3, 3>(9, 9).diagonal().setConstant(kg);
    F.block<3, 3>(12, 12).diagonal().setConstant(ka);
    x.p += x.v * kDt + 0.5 * acc * kDt * kDt;
    x.v += acc * kDt;
    x.q = (x.q * so3::exp_quat(wdt)).normalized();
    x.bg *= kg;
    x.ba *= ka;
    Mat15 Q = Mat15::Zero();
    const double qa = m.accel_noise_density * m.accel_noise_density;
    Q.block<3, 3>(0, 0).diagonal().setConstant(qa * kDt * kDt * kDt / 3.0);
    Q.block<3, 3>(0, 3).diagonal().setConstant(qa * kDt * kDt / 2.0);
    Q.block<3, 3>(3, 0).diagonal().setConstant(qa * kDt * kDt / 2.0);
    Q.block<3, 3>(3, 3).diagonal().setConstant(qa * kDt);
    Q.block<3, 3>(6, 6).diagonal().setConstant(m.gyro_noise_density * m.gyro_noise_density * kDt);
    Q.block<3, 3>(9, 9).diagonal().setConstant(m.gyro_bias.variance(kDt));
    Q.block<3, 3>(12, 12).diagonal().setConstant(m.accel_bias.variance(kDt));
    // F P F' by block rows of F (F is zero outside the blocks set above), twice.
    const auto rows_times_F = [&](const auto& B) {  // F B for B with 15 rows
      Eigen::Matrix<double, 15, 15> out;
      out.middleRows<3>(0) = B.template middleRows<3>(0) + kDt * B.template middleRows<3>(3) +
                             F.block<3, 3>(0, 6) * B.template middleRows<3>(6) + F.block<3, 3>(0, 12) * B.template middleRows<3>(12);
      out.middleRows<3>(3) = B.template middleRows<3>(3) + F.block<3, 3>(3, 6) * B.template middleRows<3>(6) +
                             F.block<3, 3>(3, 12) * B.template middleRows<3>(12);
      out.middleRows<3>(6) = F.block<3, 3>(6, 6) * B.template middleRows<3>(6) + F.block<3, 3>(6, 9) * B.template middleRows<3>(9);
      out.middleRows<3>(9) = kg * B.template middleRows<3>(9);
      out.middleRows<3>(12) = ka * B.template middleRows<3>(12);
      return out;
    };
    const Mat15 FP = rows_times_F(P);
    P = rows_times_F(FP.transpose());
    P += Q;
    symmetrize(P);

    // Antenna position update: H = [I 0 -C[l]x 0 0].
    const Eigen::Matrix3d H_theta = -x.q.toRotationMatrix() * so3::skew(kLeverArm);
    const Eigen::Vector3d y = inputs().fix[i & 63] - (x.p + x.q.toRotationMatrix() * kLeverArm);
    Eigen::Matrix<double, 15, 3> PHt = P.middleCols<3>(0);
    PHt.noalias() += P.middleCols<3>(6) * H_theta.transpose();
    Eigen::Matrix3d S = PHt.middleRows<3>(0);
    S.noalias() += H_theta * PHt.middleRows<3>(6);
    S += kR;
    symmetrize(S);
    const Eigen::LLT<Eigen::Matrix3d> llt(S);
    const double nis = y.dot(llt.solve(y));  // what a chi-square gate would test
    CTXFUSE_KEEP(nis);
    const Eigen::Matrix<double, 15, 3> K = llt.solve(PHt.transpose()).transpose();
    const Vec15 dx = K * y;
    const Mat15 K_PHt = K * PHt.transpose();
    const Eigen::Matrix<double, 15, 3> KS = K * S;
    Mat15 Pn = P;
    Pn -= K_PHt;
    Pn -= K_PHt.transpose();
    Pn.noalias() += KS * K.transpose();
    symmetrize(Pn);
    // Injection and reset: G = I but for the attitude block.
    x.p += dx.segment<3>(0);
    x.v += dx.segment<3>(3);
    x.q = (x.q * so3::exp_quat(dx.segment<3>(6))).normalized();
    x.bg += dx.segment<3>(9);
    x.ba += dx.segment<3>(12);
    const Eigen::Matrix3d Jr = so3::right_jacobian(Eigen::Vector3d(dx.segment<3>(6)));
    Pn.middleRows<3>(6) = (Jr * Pn.middleRows<3>(6)).eval();
    Pn.middleCols<3>(6) = (Pn.middleCols<3>(6) * Jr.transpose()).eval();
    P = Pn;
  }
  const InsState& state() const { return x; }
  const Mat15& cov() const { return P; }
};

// ---------------------------------------------------------------- dynamic size
struct DynamicFilter {
  models::Ins15Model m = make_model();
  InsState x = initial_belief().nominal;
  Eigen::MatrixXd P = initial_belief().cov;
  Eigen::MatrixXd R = kR;

  void step(int i) {
    using Eigen::MatrixXd;
    const ImuSample& u = inputs().imu[i & 63];
    const Eigen::Vector3d w = u.gyro - x.bg, a = u.accel - x.ba;
    const Eigen::Matrix3d C = x.q.toRotationMatrix();
    const Eigen::Vector3d acc = C * a + m.gravity;
    const Eigen::Vector3d wdt = w * kDt;
    const double kg = m.gyro_bias.decay(kDt), ka = m.accel_bias.decay(kDt);
    MatrixXd F = MatrixXd::Identity(15, 15);
    const Eigen::Matrix3d Cax = C * so3::skew(a);
    F.block(0, 3, 3, 3).diagonal().setConstant(kDt);
    F.block(0, 6, 3, 3) = -0.5 * kDt * kDt * Cax;
    F.block(0, 12, 3, 3) = -0.5 * kDt * kDt * C;
    F.block(3, 6, 3, 3) = -kDt * Cax;
    F.block(3, 12, 3, 3) = -kDt * C;
    F.block(6, 6, 3, 3) = so3::exp(wdt).transpose();
    F.block(6, 9, 3, 3) = -kDt * so3::right_jacobian(wdt);
    F.block(9, 9, 3, 3).diagonal().setConstant(kg);
    F.block(12, 12, 3, 3).diagonal().setConstant(ka);
    x.p += x.v * kDt + 0.5 * acc * kDt * kDt;
    x.v += acc * kDt;
    x.q = (x.q * so3::exp_quat(wdt)).normalized();
    x.bg *= kg;
    x.ba *= ka;
    MatrixXd Q = MatrixXd::Zero(15, 15);
    const double qa = m.accel_noise_density * m.accel_noise_density;
    Q.block(0, 0, 3, 3).diagonal().setConstant(qa * kDt * kDt * kDt / 3.0);
    Q.block(0, 3, 3, 3).diagonal().setConstant(qa * kDt * kDt / 2.0);
    Q.block(3, 0, 3, 3).diagonal().setConstant(qa * kDt * kDt / 2.0);
    Q.block(3, 3, 3, 3).diagonal().setConstant(qa * kDt);
    Q.block(6, 6, 3, 3).diagonal().setConstant(m.gyro_noise_density * m.gyro_noise_density * kDt);
    Q.block(9, 9, 3, 3).diagonal().setConstant(m.gyro_bias.variance(kDt));
    Q.block(12, 12, 3, 3).diagonal().setConstant(m.accel_bias.variance(kDt));
    P = F * P * F.transpose() + Q;
    P = (0.5 * (P + P.transpose())).eval();

    MatrixXd H = MatrixXd::Zero(3, 15);
    H.block(0, 0, 3, 3).setIdentity();
    H.block(0, 6, 3, 3) = -x.q.toRotationMatrix() * so3::skew(kLeverArm);
    const Eigen::VectorXd y = inputs().fix[i & 63] - (x.p + x.q.toRotationMatrix() * kLeverArm);
    const MatrixXd PHt = P * H.transpose();
    MatrixXd S = H * PHt + R;
    S = (0.5 * (S + S.transpose())).eval();
    const Eigen::LLT<MatrixXd> llt(S);
    const double nis = y.dot(llt.solve(y));
    CTXFUSE_KEEP(nis);
    const MatrixXd K = llt.solve(PHt.transpose()).transpose();
    const Eigen::VectorXd dx = K * y;
    const MatrixXd K_PHt = K * PHt.transpose();
    MatrixXd Pn = P - K_PHt - K_PHt.transpose() + K * S * K.transpose();
    Pn = (0.5 * (Pn + Pn.transpose())).eval();
    x.p += dx.segment<3>(0);
    x.v += dx.segment<3>(3);
    x.q = (x.q * so3::exp_quat(Eigen::Vector3d(dx.segment<3>(6)))).normalized();
    x.bg += dx.segment<3>(9);
    x.ba += dx.segment<3>(12);
    MatrixXd G = MatrixXd::Identity(15, 15);
    G.block(6, 6, 3, 3) = so3::right_jacobian(Eigen::Vector3d(dx.segment<3>(6)));
    P = G * Pn * G.transpose();
    P = (0.5 * (P + P.transpose())).eval();
  }
  const InsState& state() const { return x; }
  const Eigen::MatrixXd& cov() const { return P; }
};

// The three must agree before any of them is timed.
inline bool variants_agree() {
  EngineFilter e;
  HandWrittenFilter h;
  DynamicFilter d;
  for (int i = 0; i < 500; ++i) {
    e.step(i);
    h.step(i);
    d.step(i);
  }
  const auto close = [](const InsState& a, const InsState& b) {
    return (a.p - b.p).norm() < 1e-9 && (a.v - b.v).norm() < 1e-9 && a.q.angularDistance(b.q) < 1e-9;
  };
  return close(e.state(), h.state()) && close(e.state(), d.state()) &&
         (e.cov() - h.cov()).cwiseAbs().maxCoeff() < 1e-9 && (Eigen::MatrixXd(e.cov()) - d.cov()).cwiseAbs().maxCoeff() < 1e-9;
}

}  // namespace zero_overhead

#pragma once
// The geodetic GNSS/INS steps that bench/gins times (gins_bench.cpp says what each benchmark is).
//   Engine:      eskf::predict of models::InsNavModel<SimplifiedStrapdown> (15 states) and of
//                Augmented<..., mount 2, lever 3> (20 states), every input check on.
//   HandWritten: the same simplified strapdown and covariance prediction written out here with
//                fixed-size Eigen and no checks: the nominal update, then P+ = F P F' + Q with
//                F applied block by block (p, v, theta, bg, ba rows; the constant extra blocks
//                of the 20-state filter are the identity), as an expert writes it by hand.
// Before anything is timed both run the same 500 steps and must agree (position to 1e-9 m,
// covariance to 1e-9 relative), or the benchmark reports an error instead of a time.
#include <Eigen/Dense>

#include <array>
#include <cmath>

#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/models/ins_augment.hpp"
#include "ctxfuse/models/ins_nav.hpp"

namespace gins_bench {
using namespace ctxfuse;

using Nav15 = models::InsNavModel<models::SimplifiedStrapdown>;
using Nav20 = models::Augmented<Nav15, StateBlock<"mount", 2>, StateBlock<"lever", 3>>;

constexpr double kDt = 0.01;
constexpr double kDeg = 3.14159265358979323846 / 180.0;
// Noise figures of an automotive MEMS IMU (the simulator's defaults, sim/config.hpp).
constexpr double kGyroDensity = 8.7e-5, kAccelDensity = 1.0e-3;
constexpr double kGyroBiasSigma = 8.7e-5, kAccelBiasSigma = 0.02, kBiasTau = 300.0;

/// 64 IMU increments that keep every term of F non-trivial (turning, accelerating).
struct Inputs {
  std::array<models::BodyIncrements, 64> imu;
  Inputs() {
    for (int i = 0; i < 64; ++i) {
      imu[i].dtheta = kDt * Eigen::Vector3d(0.01 * std::sin(0.3 * i), -0.02 * std::cos(0.2 * i), 0.1 + 0.05 * std::sin(0.1 * i));
      imu[i].dv = kDt * Eigen::Vector3d(0.3 * std::cos(0.15 * i), 0.1 * std::sin(0.25 * i), -9.79 + 0.05 * std::sin(0.4 * i));
    }
  }
};
inline const Inputs& inputs() {
  static const Inputs in;
  return in;
}

inline Nav15 make_nav15() {
  Nav15 m;
  m.gyro_noise_density = kGyroDensity;
  m.accel_noise_density = kAccelDensity;
  m.gyro_bias = models::GaussMarkov{kGyroBiasSigma * std::sqrt(2.0 / kBiasTau), kBiasTau};
  m.accel_bias = models::GaussMarkov{kAccelBiasSigma * std::sqrt(2.0 / kBiasTau), kBiasTau};
  return m;
}
inline Nav20 make_nav20() {
  Nav20 m;
  m.base = make_nav15();
  return m;
}

inline models::NavState start_nav() {
  models::NavState x;
  x.get<"p">() = Eigen::Vector3d(24.85 * kDeg, 102.7 * kDeg, 1890.0);
  x.get<"v">() = Eigen::Vector3d(5.0, 3.0, 0.1);
  x.get<"theta">() = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.1, -0.2, 1.0).normalized()));
  x.get<"bg">() = Eigen::Vector3d(1e-4, -2e-4, 5e-5);
  x.get<"ba">() = Eigen::Vector3d(0.01, -0.02, 0.015);
  return x;
}

template <int N>
SquareMatrix<N> start_cov() {
  Vector<N> sd = Vector<N>::Constant(0.05);
  sd.template head<15>() << 3, 3, 5, 0.3, 0.3, 0.3, kDeg, kDeg, 3 * kDeg, 1e-3, 1e-3, 1e-3, 0.05, 0.05, 0.05;
  SquareMatrix<N> P = sd.cwiseAbs2().asDiagonal();
  P(0, 3) = P(3, 0) = 0.2;  // some correlation, so no product is trivially diagonal
  P(6, 13) = P(13, 6) = 1e-5;
  return P;
}

/// The hand-written filter: N = 15, or 20 with five constant extra states after the 15.
template <int N>
struct HandWritten {
  using Mat = Eigen::Matrix<double, N, N>;
  Eigen::Vector3d llh, v, bg, ba;
  Eigen::Quaterniond q;
  Mat P;

  HandWritten() {
    const models::NavState x = start_nav();
    llh = x.get<"p">();
    v = x.get<"v">();
    q = x.get<"theta">();
    bg = x.get<"bg">();
    ba = x.get<"ba">();
    P = start_cov<N>();
  }

  static Eigen::Matrix3d skew(const Eigen::Vector3d& w) {
    Eigen::Matrix3d S;
    S << 0, -w(2), w(1), w(2), 0, -w(0), -w(1), w(0), 0;
    return S;
  }
  // WGS-84 radii and Somigliana normal gravity with its second-order height term.
  static Eigen::Vector3d metres_per_llh(double lat, double h) {
    const double a = 6378137.0, f = 1.0 / 298.257223563, e2 = f * (2.0 - f);
    const double w2 = 1.0 - e2 * std::sin(lat) * std::sin(lat);
    return {a * (1.0 - e2) / (w2 * std::sqrt(w2)) + h, (a / std::sqrt(w2) + h) * std::cos(lat), -1.0};
  }
  static double gravity(double lat, double h) {
    const double a = 6378137.0, f = 1.0 / 298.257223563, e2 = f * (2.0 - f), m = 0.00344978650684;
    const double s2 = std::sin(lat) * std::sin(lat);
    const double g0 = 9.7803253359 * (1.0 + 0.00193185265241 * s2) / std::sqrt(1.0 - e2 * s2);
    return g0 * (1.0 - 2.0 / a * (1.0 + f + m - 2.0 * f * s2) * h + 3.0 * h * h / (a * a));
  }

  // Rows p, v, theta, bg, ba of F times a 15 x K block.
  struct F15 {
    double dt, kg, ka;
    Eigen::Matrix3d Fpt, Fpa, Fvt, Fva, Ftt, Ftg;
    template <class In, class Out>
    void apply(const In& X, Out& Y) const {
      Y.template middleRows<3>(0).noalias() = X.template middleRows<3>(0) + dt * X.template middleRows<3>(3);
      Y.template middleRows<3>(0).noalias() += Fpt * X.template middleRows<3>(6);
      Y.template middleRows<3>(0).noalias() += Fpa * X.template middleRows<3>(12);
      Y.template middleRows<3>(3).noalias() = X.template middleRows<3>(3);
      Y.template middleRows<3>(3).noalias() += Fvt * X.template middleRows<3>(6);
      Y.template middleRows<3>(3).noalias() += Fva * X.template middleRows<3>(12);
      Y.template middleRows<3>(6).noalias() = Ftt * X.template middleRows<3>(6);
      Y.template middleRows<3>(6).noalias() += Ftg * X.template middleRows<3>(9);
      Y.template middleRows<3>(9) = kg * X.template middleRows<3>(9);
      Y.template middleRows<3>(12) = ka * X.template middleRows<3>(12);
    }
  };

  void step(const models::BodyIncrements& u, double dt) {
    const double tau = kBiasTau;
    const double kg = std::exp(-dt / tau), ka = kg;
    const Eigen::Vector3d dth = u.dtheta - bg * dt;
    const Eigen::Vector3d dv = u.dv - ba * dt;
    const Eigen::Matrix3d C = q.toRotationMatrix();
    const Eigen::Vector3d v_new = v + C * dv + Eigen::Vector3d(0.0, 0.0, gravity(llh(0), llh(2)) * dt);
    const Eigen::Vector3d per = metres_per_llh(llh(0), llh(2));
    // Exp(dth) and the right Jacobian Jr(dth), half-angle form.
    const double th2 = dth.squaredNorm(), th = std::sqrt(th2);
    const double s = std::sin(0.5 * th), c = std::cos(0.5 * th);
    const Eigen::Quaterniond q_step(c, s / th * dth(0), s / th * dth(1), s / th * dth(2));
    const Eigen::Matrix3d K = skew(dth);
    const Eigen::Matrix3d Jr = Eigen::Matrix3d::Identity() - (2.0 * s * s) / th2 * K + (th - 2.0 * s * c) / (th2 * th) * K * K;

    F15 F{dt, kg, ka, {}, {}, {}, {}, {}, {}};
    const Eigen::Matrix3d C_ax = C * skew(dv / dt);
    F.Fpt = -0.5 * dt * dt * C_ax;
    F.Fpa = -0.5 * dt * dt * C;
    F.Fvt = -dt * C_ax;
    F.Fva = -dt * C;
    F.Ftt = q_step.toRotationMatrix().transpose();
    F.Ftg = -dt * Jr;

    llh += (0.5 * (v + v_new) * dt).cwiseQuotient(per);
    v = v_new;
    q = (q * q_step).normalized();
    bg *= kg;
    ba *= ka;

    // T = F P (the extra rows stay), then P+ = F T' (= F P F', symmetric), then + Q.
    Mat T;
    F.apply(P.template topRows<15>(), T);
    if constexpr (N > 15) T.template bottomRows<N - 15>() = P.template bottomRows<N - 15>();
    const Mat Tt = T.transpose();
    F.apply(Tt.template topRows<15>(), P);
    if constexpr (N > 15) P.template bottomRows<N - 15>() = Tt.template bottomRows<N - 15>();
    const double qa = kAccelDensity * kAccelDensity;
    const double gm = kGyroBiasSigma * kGyroBiasSigma * (1.0 - std::exp(-2.0 * dt / tau));
    const double am = kAccelBiasSigma * kAccelBiasSigma * (1.0 - std::exp(-2.0 * dt / tau));
    for (int i = 0; i < 3; ++i) {
      P(i, i) += qa * dt * dt * dt / 3.0;
      P(i, 3 + i) += qa * dt * dt / 2.0;
      P(3 + i, i) += qa * dt * dt / 2.0;
      P(3 + i, 3 + i) += qa * dt;
      P(6 + i, 6 + i) += kGyroDensity * kGyroDensity * dt;
      P(9 + i, 9 + i) += gm;
      P(12 + i, 12 + i) += am;
    }
    P = (0.5 * (P + P.transpose())).eval();
  }
};

template <class Model>
eskf::Belief<Model> engine_start() {
  eskf::Belief<Model> b;
  if constexpr (requires { Model::set_base_part(b.nominal, start_nav()); }) Model::set_base_part(b.nominal, start_nav());
  else b.nominal = start_nav();
  b.cov = start_cov<Model::dim>();
  return b;
}

/// Largest position gap [m] and relative covariance gap after `steps` steps of both.
template <class Model>
bool variants_agree(const Model& model, int steps = 500) {
  eskf::Belief<Model> b = engine_start<Model>();
  HandWritten<Model::dim> h;
  for (int k = 0; k < steps; ++k) {
    const auto& u = inputs().imu[static_cast<std::size_t>(k % 64)];
    if (!eskf::predict(model, b, u, kDt).accepted()) return false;
    h.step(u, kDt);
  }
  const Eigen::Vector3d& llh = b.nominal.template get<"p">();
  const double dpos = earth::GeodeticRetraction::difference(llh, h.llh).norm();
  const double dcov = (b.cov - h.P).cwiseAbs().maxCoeff() / b.cov.cwiseAbs().maxCoeff();
  return dpos < 1e-9 && dcov < 1e-9;
}

}  // namespace gins_bench

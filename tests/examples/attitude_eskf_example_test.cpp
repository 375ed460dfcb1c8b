// examples/attitude_eskf.hpp against the same error-state filter written out by hand with plain
// Eigen (quaternion product, rotation-vector exponential by AngleAxis, the right Jacobian's
// closed form, Kalman gain, Joseph update, injection and reset), and the model's Jacobians
// against central differences through its own retraction.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <boost/math/distributions/chi_squared.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "attitude_eskf.hpp"

namespace {
namespace ae = attitude_eskf;
using M3 = Eigen::Matrix3d;
using V3 = Eigen::Vector3d;
using M6 = Eigen::Matrix<double, 6, 6>;

M3 hat(const V3& v) {
  M3 m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}
Eigen::Quaterniond exp_q(const V3& phi) {
  const double a = phi.norm();
  return a == 0.0 ? Eigen::Quaterniond::Identity() : Eigen::Quaterniond(Eigen::AngleAxisd(a, phi / a));
}
/// Jr(phi) = I - (1 - cos a) / a^2 [phi]x + (a - sin a) / a^3 [phi]x^2 (Chirikjian; Sola, eq. 143).
M3 right_jacobian(const V3& phi) {
  const double a = phi.norm();
  const M3 K = hat(phi);
  return M3::Identity() - (1 - std::cos(a)) / (a * a) * K + (a - std::sin(a)) / (a * a * a) * K * K;
}

/// The filter by hand: the same model, step by step.
struct HandEskf {
  Eigen::Quaterniond q;
  V3 b;
  M6 P;
  double gyro_density, bias_walk;
  static constexpr double kGate = 16.266236196238;  // chi-square, 3 dof, p = 0.999

  void predict(const V3& w, double dt) {
    const V3 phi = (w - b) * dt;
    M6 F = M6::Identity();
    F.topLeftCorner<3, 3>() = exp_q(phi).toRotationMatrix().transpose();
    F.topRightCorner<3, 3>() = -right_jacobian(phi) * dt;
    M6 Q = M6::Zero();
    Q.topLeftCorner<3, 3>() = M3::Identity() * gyro_density * gyro_density * dt;
    Q.bottomRightCorner<3, 3>() = M3::Identity() * bias_walk * bias_walk * dt;
    q = (q * exp_q(phi)).normalized();
    P = F * P * F.transpose() + Q;
  }
  bool update(const V3& world, double sigma, const V3& z) {
    const V3 body = q.conjugate() * world;
    Eigen::Matrix<double, 3, 6> H = Eigen::Matrix<double, 3, 6>::Zero();
    H.leftCols<3>() = hat(body);
    const M3 R = M3::Identity() * sigma * sigma;
    const M3 S = H * P * H.transpose() + R;
    const V3 y = z - body;
    if (y.dot(S.inverse() * y) > kGate) return false;
    const Eigen::Matrix<double, 6, 3> K = P * H.transpose() * S.inverse();
    const Eigen::Matrix<double, 6, 1> dx = K * y;
    const M6 IKH = M6::Identity() - K * H;
    P = IKH * P * IKH.transpose() + K * R * K.transpose();
    q = (q * exp_q(dx.head<3>())).normalized();
    b += dx.tail<3>();
    M6 G = M6::Identity();
    G.topLeftCorner<3, 3>() -= 0.5 * hat(dx.head<3>());
    P = G * P * G.transpose();
    return true;
  }
};

TEST(AttitudeEskfExample, EveryEpochIsTheFilterWrittenOutByHand) {
  const ae::Run r = ae::run();
  HandEskf hand{r.initial.nominal.q, r.initial.nominal.bias, r.initial.cov, r.model.gyro_noise_density,
                r.model.bias_random_walk};
  double angle = 0.0, bias = 0.0, cov = 0.0;
  int gated = 0;
  for (const auto& e : r.epochs) {
    ASSERT_TRUE(e.predicted) << e.t;
    hand.predict(e.gyro, r.settings.imu_dt);
    if (e.has_fix) {
      const bool up = hand.update(r.up.world, r.up.sigma, e.up);
      const bool north = hand.update(r.north.world, r.north.sigma, e.north);
      ASSERT_EQ(up, e.up_updated.accepted()) << e.t;
      ASSERT_EQ(north, e.north_updated.accepted()) << e.t;
      gated += !up + !north;
    }
    angle = std::max(angle, (hand.q.conjugate() * e.belief.nominal.q).vec().norm() * 2.0);
    bias = std::max(bias, (hand.b - e.belief.nominal.bias).cwiseAbs().maxCoeff());
    cov = std::max(cov, ((hand.P - e.belief.cov).array() / hand.P.diagonal().maxCoeff()).abs().maxCoeff());
  }
  std::printf("6000 epochs, %d updates gated: largest gaps: attitude %.1e rad, bias %.1e rad/s, covariance %.1e "
              "(relative)\n", gated, angle, bias, cov);
  EXPECT_LT(angle, 1e-10);
  EXPECT_LT(bias, 1e-12);
  EXPECT_LT(cov, 1e-10);
}

TEST(AttitudeEskfExample, TheModelsJacobiansAreCentralDifferencesThroughItsRetraction) {
  const ae::GyroAttitude model;
  ae::Attitude x;
  x.q = exp_q(V3(0.3, -1.1, 2.0));
  x.bias = V3(0.02, -0.01, 0.03);
  const V3 w(0.4, -0.2, 0.9);
  const double dt = 0.05, h = 1e-6;
  ctxfuse::SquareMatrix<6> F;
  const ae::Attitude y = model.predict(x, w, dt, &F);
  ae::BodyDirection dir;
  dir.world = V3(0.5, 0.0, -0.866025403784).normalized();
  ctxfuse::Matrix<3, 6> H;
  const V3 z = dir.predict(x, &H);
  for (int j = 0; j < 6; ++j) {
    ctxfuse::Vector<6> d = ctxfuse::Vector<6>::Zero();
    d(j) = h;
    const ae::Attitude xp = model.inject(x, d), xm = model.inject(x, -d);
    const ctxfuse::Vector<6> f_col =
        (model.difference(model.predict(xp, w, dt, nullptr), y) - model.difference(model.predict(xm, w, dt, nullptr), y)) /
        (2 * h);
    const V3 h_col = (dir.predict(xp, nullptr) - dir.predict(xm, nullptr)) / (2 * h);
    EXPECT_LT((f_col - F.col(j)).cwiseAbs().maxCoeff(), 1e-8) << "F column " << j;
    EXPECT_LT((h_col - H.col(j)).cwiseAbs().maxCoeff(), 1e-8) << "H column " << j;
  }
  (void)z;
  // The retraction's inverse: (x [+] d) [-] x = d.
  const ctxfuse::Vector<6> d = (ctxfuse::Vector<6>() << 0.1, -0.2, 0.05, 1e-3, -2e-3, 5e-4).finished();
  EXPECT_LT((model.difference(model.inject(x, d), x) - d).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(AttitudeEskfExample, ItsErrorsAgreeWithItsCovariance) {
  // Monte Carlo over 200 seeds: the normalised estimation error squared at the end of a 20 s run,
  // e' P^-1 e over attitude and bias (6 dof), averaged over the runs, lies within the two-sided
  // 99 % interval of a chi-square of 1200 dof divided by 200 when the filter is consistent.
  constexpr int kRuns = 200;
  double nees = 0.0;
  for (int seed = 1; seed <= kRuns; ++seed) {
    ae::Settings s;
    s.seed = static_cast<std::uint64_t>(seed);
    s.duration_s = 20.0;
    const ae::Run r = ae::run(s);
    const auto& last = r.epochs.back();
    Eigen::Matrix<double, 6, 1> e;
    e << last.error, s.true_bias - last.belief.nominal.bias;
    nees += e.dot(last.belief.cov.ldlt().solve(e));
  }
  nees /= kRuns;
  const boost::math::chi_squared chi2(6 * kRuns);
  const double lo = boost::math::quantile(chi2, 0.005) / kRuns, hi = boost::math::quantile(chi2, 0.995) / kRuns;
  std::printf("average NEES over %d runs %.2f (6 dof; 99 %% interval %.2f to %.2f)\n", kRuns, nees, lo, hi);
  EXPECT_GT(nees, lo);
  EXPECT_LT(nees, hi);
}

}  // namespace

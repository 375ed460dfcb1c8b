#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/models/ins.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/testing/jacobians.hpp"

namespace {
using namespace ctxfuse;
using models::Ins15Layout;
using models::Ins15Model;
using models::InsState;

InsState sample_state() {
  InsState x;
  x.p = {10.0, -3.0, 1.5};
  x.v = {4.0, 1.0, -0.2};
  x.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, -0.3, 1.0).normalized()));
  x.bg = {0.01, -0.02, 0.005};
  x.ba = {0.1, -0.05, 0.2};
  return x;
}

TEST(Eskf, ResetJacobianIsTheDerivativeOfTheErrorReparametrisation) {
  // True state t = x [+] e_old = (x [+] dx) [+] e_new, so e_new(e_old) = (x [+] e_old) [-] (x [+] dx);
  // the reset Jacobian is its derivative at e_old = dx.
  const Ins15Model m;
  const InsState x = sample_state();
  Vector<15> dx;
  dx << 0.1, -0.2, 0.05, 0.01, 0.02, -0.03, 0.08, -0.15, 0.3, 1e-3, -2e-3, 5e-4, 0.01, 0.02, -0.01;
  const InsState x_new = m.inject(x, dx);
  auto e_new = [&](const Vector<15>& e_old) -> Vector<15> { return m.difference(m.inject(x, e_old), x_new); };
  EXPECT_LT(e_new(dx).norm(), 1e-12);
  const SquareMatrix<15> G_num = ctxfuse::testing::central_jacobian<15, 15>(e_new, dx, 1e-6);
  const SquareMatrix<15> G = m.reset_jacobian(x, dx);
  EXPECT_LT((G - G_num).cwiseAbs().maxCoeff(), 1e-8);
  // And the common first-order form I - [dtheta/2]x is only an approximation of it.
  const SquareMatrix<3> first_order = SquareMatrix<3>::Identity() - 0.5 * so3::skew(Ins15Layout::get<"theta">(dx));
  EXPECT_GT((Ins15Layout::cov<"theta">(G) - first_order).cwiseAbs().maxCoeff(), 1e-4);
}

TEST(Eskf, UpdateInjectsTheKalmanCorrectionAndResetsTheCovariance) {
  const Ins15Model m;
  models::GnssPosition<> gnss;
  gnss.lever_arm = {0.5, -0.2, 1.1};
  gnss.R = Vector<3>(0.5, 0.6, 1.2).asDiagonal();
  eskf::Belief<Ins15Model> b;
  b.nominal = sample_state();
  SquareMatrix<15> A = SquareMatrix<15>::Random();
  b.cov = 0.05 * A * A.transpose() + 0.1 * SquareMatrix<15>::Identity();
  const eskf::Belief<Ins15Model> prior = b;
  const Vector<3> z(10.8, -2.5, 2.9);

  Vector<15> dx_applied;
  ASSERT_TRUE(eskf::update(m, gnss, b, z, policies::NoGate{}, {}, &dx_applied));

  // Reference written out with dynamic matrices and an explicit inverse.
  const Eigen::Matrix3d C = prior.nominal.q.toRotationMatrix();
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(3, 15);
  H.block(0, 0, 3, 3).setIdentity();
  H.block(0, 6, 3, 3) = -C * so3::skew(gnss.lever_arm);
  const Eigen::MatrixXd P = prior.cov;
  const Eigen::MatrixXd S = H * P * H.transpose() + Eigen::MatrixXd(gnss.R);
  const Eigen::MatrixXd K = P * H.transpose() * S.inverse();
  const Eigen::VectorXd y = z - (prior.nominal.p + C * gnss.lever_arm);
  const Eigen::VectorXd dx = K * y;
  const Eigen::MatrixXd P_post = (Eigen::MatrixXd::Identity(15, 15) - K * H) * P;
  const Eigen::MatrixXd G = m.reset_jacobian(prior.nominal, dx);
  const Eigen::MatrixXd P_reset = G * P_post * G.transpose();

  EXPECT_LT((dx_applied - dx).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT(m.difference(b.nominal, m.inject(prior.nominal, dx)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((b.cov - P_reset).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_NEAR(b.nominal.q.norm(), 1.0, 1e-14);
}

// A vector-space nominal state: the ESKF must then be exactly the EKF.
struct VectorCv {
  using L = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;
  using State = Vector<4>;
  using Input = NoInput;
  static constexpr int dim = 4;
  models::ConstantVelocity<L, 2> cv{0.3};
  State predict(const State& x, const Input& u, double dt, SquareMatrix<4>* F) const { return cv.predict(x, u, dt, F); }
  SquareMatrix<4> noise(const State& x, const Input& u, double dt) const { return cv.noise(x, u, dt); }
  State inject(const State& x, const Vector<4>& dx) const { return x + dx; }
  Vector<4> difference(const State& a, const State& b) const { return a - b; }
};

TEST(Eskf, WithVectorNominalEqualsTheEkf) {
  VectorCv model;
  models::RangeToPoint<VectorCv::L, 2> range;
  range.anchor = {5.0, 5.0};
  Eskf<VectorCv> eskf_filter(model, {Vector<4>(0, 0, 1, 0.5), SquareMatrix<4>::Identity()});
  Ekf<models::ConstantVelocity<VectorCv::L, 2>> ekf_filter(model.cv, {Vector<4>(0, 0, 1, 0.5), SquareMatrix<4>::Identity()});
  for (int k = 0; k < 50; ++k) {
    ASSERT_TRUE(eskf_filter.predict({}, 0.1));
    ASSERT_TRUE(ekf_filter.predict({}, 0.1));
    const Vector<1> z(std::hypot(5.0 - 0.1 * k, 5.0 - 0.05 * k) + 0.01 * ((k % 5) - 2));
    ASSERT_TRUE(eskf_filter.update(range, z));
    ASSERT_TRUE(ekf_filter.update(range, z));
  }
  EXPECT_LT((eskf_filter.nominal() - ekf_filter.belief().mean).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((eskf_filter.belief().cov - ekf_filter.belief().cov).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Eskf, StaticLevelImuWithPositionFixesStaysPutAndShrinksPositionVariance) {
  Ins15Model m;
  models::GnssPosition<> gnss;
  gnss.R = SquareMatrix<3>::Identity() * 0.25;
  eskf::Belief<Ins15Model> b;
  b.cov = SquareMatrix<15>::Identity() * 1e-2;
  Ins15Layout::cov<"p">(b.cov) = SquareMatrix<3>::Identity() * 100.0;
  Eskf<Ins15Model, policies::ChiSquareGate> f(m, b, {}, policies::ChiSquareGate(0.999));
  models::ImuSample u;
  u.accel = -m.gravity;  // at rest, level: specific force opposes gravity
  for (int k = 0; k < 500; ++k) {
    ASSERT_TRUE(f.predict(u, 0.01));
    if (k % 100 == 99) {
      ASSERT_TRUE(f.update(gnss, Vector<3>::Zero()));
    }
  }
  EXPECT_LT(f.nominal().p.norm(), 1e-9);
  EXPECT_LT(f.nominal().v.norm(), 1e-9);
  EXPECT_LT(Ins15Layout::cov<"p">(f.belief().cov).trace(), 3.0 * 0.25);
}

}  // namespace

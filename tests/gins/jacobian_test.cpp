// Every measurement Jacobian of the geodetic INS against central differences on the manifold:
// column i of H is d residual(h(x [+] e), h(x)) / d e_i at e = 0, on the 15-state and the
// augmented 20-state layouts (where the lever arm and mounting blocks have columns too), and
// with an odometer scale-factor block.
#include <gtest/gtest.h>

#include "ctxfuse/models/ins_updates.hpp"
#include "states.hpp"

namespace {
using namespace ctxfuse;
using namespace ctxfuse::models;

template <class Model, class Meas>
void expect_jacobian_matches(const Model& model, const Meas& meas, const typename Model::State& x) {
  constexpr int N = Model::dim, M = Meas::dim;
  Matrix<M, N> H;
  const Vector<M> z0 = meas.predict(x, &H);
  Matrix<M, N> H_num;
  for (int i = 0; i < N; ++i) {
    // The fix is in radians of latitude (ulp ~1e-16 rad, ~1e-9 m): a step must move it well
    // above roundoff. 1 cm of position (exact: linear there) and 1e-3 of the other errors
    // (truncation ~h^2/6 ~ 2e-7 relative).
    const double h = i < 3 ? 1e-2 : 1e-3;
    Vector<N> ep = Vector<N>::Zero(), em = Vector<N>::Zero();
    ep(i) = h;
    em(i) = -h;
    Vector<M> zp = meas.predict(model.inject(x, ep), nullptr), zm = meas.predict(model.inject(x, em), nullptr);
    if constexpr (requires { meas.residual(zp, z0); }) {
      zp = meas.residual(zp, z0);
      zm = meas.residual(zm, z0);
    } else {
      zp -= z0;
      zm -= z0;
    }
    H_num.col(i) = (zp - zm) / (2.0 * h);
  }
  for (int r = 0; r < M; ++r) {
    const double scale = std::max(H.row(r).cwiseAbs().maxCoeff(), 1e-300);
    EXPECT_LT((H.row(r) - H_num.row(r)).cwiseAbs().maxCoeff() / scale, 2e-6)
        << "row " << r << "\nH     " << H.row(r) << "\nH_num " << H_num.row(r);
  }
}

template <class Model>
void check_all(const Model& model, const typename Model::State& x) {
  using S = typename Model::State;
  GnssGeodeticPosition<S> pos;
  pos.lever_arm = {0.4, -0.3, -1.1};
  expect_jacobian_matches(model, pos, x);
  GnssVelocity<S> vel;
  vel.lever_arm = {0.4, -0.3, -1.1};
  vel.gyro = {0.2, -0.1, 0.5};
  expect_jacobian_matches(model, vel, x);
  expect_jacobian_matches(model, ZeroVelocity<S>{}, x);
  expect_jacobian_matches(model, Heading<S>{}, x);
  NonHolonomic<S> nhc;
  nhc.vehicle.gyro = {0.05, 0.02, 0.3};
  nhc.vehicle.lever_arm = {-1.0, 0.1, 0.5};    // used only without a "lever" block
  nhc.vehicle.mount = {0.03, -0.04};           // used only without a "mount" block
  expect_jacobian_matches(model, nhc, x);
  NonHolonomicWithSpeed<S> nhs;
  nhs.vehicle = nhc.vehicle;
  expect_jacobian_matches(model, nhs, x);
}

TEST(GinsJacobians, EveryMeasurementOnTheFifteenStateLayout) { check_all(test::Nav15{}, test::sample_nav_state()); }

TEST(GinsJacobians, EveryMeasurementOnTheAugmentedLayout) { check_all(test::Nav20{}, test::sample_nav20_state()); }

TEST(GinsJacobians, EveryMeasurementWithAnOdometerScaleBlock) { check_all(test::Nav16{}, test::sample_nav16_state()); }

// The scale block enters the forward speed only: (1 + k) u_0, and its column is u_0.
TEST(GinsJacobians, OdometerScaleScalesTheForwardSpeedOnly) {
  const test::Nav16::State x = test::sample_nav16_state();
  NonHolonomicWithSpeed<test::Nav16::State> scaled;
  NonHolonomicWithSpeed<models::NavState> plain;
  scaled.vehicle.gyro = plain.vehicle.gyro = {0.05, 0.02, 0.3};
  const Vector<3> u = plain.predict(test::Nav16::base_part(x), nullptr);
  Matrix<3, 16> H;
  const Vector<3> z = scaled.predict(x, &H);
  EXPECT_NEAR(z(0), 1.013 * u(0), 1e-12);
  EXPECT_TRUE(z.tail<2>() == u.tail<2>());
  EXPECT_NEAR(H(0, 15), u(0), 1e-12);
  EXPECT_EQ(H(1, 15), 0.0);
  EXPECT_EQ(H(2, 15), 0.0);
}

TEST(GinsJacobians, HeadingNearNorthAndAcrossPi) {
  models::NavState x = test::sample_nav_state();
  for (double yaw : {0.0, 179.9 * test::kDeg, -179.9 * test::kDeg, 90.0 * test::kDeg}) {
    x.get<"theta">() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                       Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitX());
    expect_jacobian_matches(test::Nav15{}, Heading<models::NavState>{}, x);
    EXPECT_NEAR(Heading<models::NavState>{}.predict(x, nullptr)(0), yaw, 1e-12);
  }
}

}  // namespace

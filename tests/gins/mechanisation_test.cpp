// Mechanisation against analytic trajectories: at rest (gravity only for the simplified
// strapdown, gravity and earth rate for the full one), a constant-rate turn, the sculling
// correction of a rotating body under a constant specific force, the transition Jacobian
// against central differences on the manifold, and the input adapter (mounting, delay, dt).
#include <gtest/gtest.h>

#include "ctxfuse/models/earth.hpp"
#include "ctxfuse/models/ins_input.hpp"
#include "ctxfuse/models/ins_nav.hpp"
#include "states.hpp"

namespace {
using namespace ctxfuse;
using namespace ctxfuse::models;
using Full = InsNavModel<FullStrapdown>;
using Simple = InsNavModel<SimplifiedStrapdown>;
using test::kDeg;

NavState at_rest_state(double heading) {
  NavState x;
  x.get<"p">() = Eigen::Vector3d(40.0 * kDeg, -86.0 * kDeg, 210.0);
  x.get<"theta">() = Eigen::Quaterniond(Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()) *
                                        Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitY()));
  return x;
}

double angle_between(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) { return a.angularDistance(b); }

TEST(Mechanisation, SimplifiedAtRestStaysPutUnderGravityAlone) {
  const Simple m;
  const NavState x0 = at_rest_state(0.5);
  const double dt = 0.01;
  const Eigen::Matrix3d C = x0.get<"theta">().toRotationMatrix();
  BodyIncrements u;
  u.dv = -C.transpose() * Eigen::Vector3d(0, 0, earth::normal_gravity(x0.get<"p">()(0), 210.0)) * dt;
  NavState x = x0;
  for (int k = 0; k < 60000; ++k) x = m.predict(x, u, dt, nullptr);  // 10 minutes at 100 Hz
  EXPECT_LT(x.get<"v">().norm(), 1e-9);
  EXPECT_LT(m.difference(x, x0).head<3>().norm(), 1e-6);
  EXPECT_LT(angle_between(x.get<"theta">(), x0.get<"theta">()), 1e-12);
}

TEST(Mechanisation, FullAtRestStaysPutUnderGravityAndEarthRate) {
  const Full m;
  const NavState x0 = at_rest_state(0.5);
  const double dt = 0.01, lat = x0.get<"p">()(0);
  const Eigen::Matrix3d C = x0.get<"theta">().toRotationMatrix();
  BodyIncrements u;
  // A body fixed to the earth turns with it: the gyros read the earth rate.
  u.dtheta = C.transpose() * earth::earth_rate_ned(lat) * dt;
  u.dv = -C.transpose() * Eigen::Vector3d(0, 0, earth::normal_gravity(lat, 210.0)) * dt;
  NavState x = x0;
  for (int k = 0; k < 360000; ++k) {  // one hour at 100 Hz
    x = m.predict(x, u, dt, nullptr);
    u.prev_dtheta = u.dtheta;
    u.prev_dv = u.dv;
    u.has_previous = true;
  }
  EXPECT_LT(angle_between(x.get<"theta">(), x0.get<"theta">()), 1e-9);
  EXPECT_LT(x.get<"v">().norm(), 1e-6);
  EXPECT_LT(m.difference(x, x0).head<3>().norm(), 1e-3);

  // The same gyro readings in the simplified mechanisation, which has no earth rate, turn the
  // attitude by the earth rate times the time: 15.04 deg in the hour.
  const Simple s;
  NavState y = x0;
  for (int k = 0; k < 360000; ++k) y = s.predict(y, u, dt, nullptr);
  EXPECT_NEAR(angle_between(y.get<"theta">(), x0.get<"theta">()), earth::kRate * 3600.0, 1e-9);
}

TEST(Mechanisation, ConstantRateTurnFollowsTheCircle) {
  // 10 m/s on a circle of 50 m radius (yaw rate 0.2 rad/s), level, for 60 s at 100 Hz. The
  // increments are exact: dtheta = w dt about down and dv, resolved in the body frame at the
  // start of the step, is the integral of the centripetal force turning with the body.
  const Simple m;
  const double V = 10.0, w = 0.2, dt = 0.01, psi0 = 0.3;
  NavState x0 = at_rest_state(psi0);
  x0.get<"theta">() = Eigen::Quaterniond(Eigen::AngleAxisd(psi0, Eigen::Vector3d::UnitZ()));
  // On the equator: elsewhere metres east per radian change by tan(lat) per radian of latitude
  // (1.3e-3 m over this circle at 40 deg), which the flat analytic circle does not have.
  x0.get<"p">()(0) = 0.0;
  x0.get<"v">() = Eigen::Vector3d(V * std::cos(psi0), V * std::sin(psi0), 0.0);
  BodyIncrements u;
  u.dtheta = Eigen::Vector3d(0, 0, w * dt);
  NavState x = x0;
  const int steps = 6000;
  for (int k = 0; k < steps; ++k) {
    // Gravity where the car is (it changes by 5e-8 m/s^2 per metre north here).
    const double g = earth::normal_gravity(x.get<"p">()(0), x.get<"p">()(2));
    u.dv = Eigen::Vector3d(V * (std::cos(w * dt) - 1.0), V * std::sin(w * dt), -g * dt);
    x = m.predict(x, u, dt, nullptr);
  }
  const double T = steps * dt, psi = psi0 + w * T;
  EXPECT_NEAR(heading_of(x.get<"theta">().toRotationMatrix()), PlanarAngleRetraction::wrap(psi), 1e-9);
  EXPECT_LT((x.get<"v">() - Eigen::Vector3d(V * std::cos(psi), V * std::sin(psi), 0.0)).norm(), 1e-9);
  const Eigen::Vector3d ned = m.difference(x, x0).head<3>();
  const Eigen::Vector3d truth(V / w * (std::sin(psi) - std::sin(psi0)), -V / w * (std::cos(psi) - std::cos(psi0)), 0.0);
  // Trapezoidal position: the chord of each step is short by (w dt / 2)^2 / 3 relative, i.e.
  // 2e-4 m over the 600 m driven; the meridian radius moves by 1e-10 relative over the circle.
  EXPECT_LT((ned - truth).norm(), 5e-4) << ned.transpose() << " vs " << truth.transpose();
}

TEST(Mechanisation, ScullingCorrectsTheVelocityIncrementOfARotatingBody) {
  // Body turning at 1 rad/s about down with a constant 2 m/s^2 forward specific force: the
  // accelerometers integrate (2 dt, 0, 0) in their turning axes; resolved at the start of the
  // step the increment is (2 sin(w dt) / w, 2 (1 - cos(w dt)) / w, 0).
  const double w = 1.0, a = 2.0, dt = 0.01;
  NavState x = at_rest_state(0.0);
  x.get<"theta">() = Eigen::Quaterniond::Identity();
  const double g = earth::normal_gravity(x.get<"p">()(0), 210.0);
  BodyIncrements u;
  u.dtheta = Eigen::Vector3d(0, 0, w * dt);
  u.dv = Eigen::Vector3d(a * dt, 0, -g * dt);
  u.prev_dtheta = u.dtheta;
  u.prev_dv = u.dv;
  u.has_previous = true;
  const Eigen::Vector3d exact(a * std::sin(w * dt) / w, a * (1.0 - std::cos(w * dt)) / w, 0.0);
  const Eigen::Vector3d v_full = Full{}.predict(x, u, dt, nullptr).get<"v">();
  const Eigen::Vector3d v_simple = Simple{}.predict(x, u, dt, nullptr).get<"v">();
  // Without the correction the error is a w dt^2 / 2 = 1e-4 m/s; with it, third order (the
  // down axis also carries g dt x the rotation, which the correction handles the same way).
  EXPECT_GT((v_simple.head<2>() - exact.head<2>()).norm(), 0.9e-4);
  EXPECT_LT((v_full.head<2>() - exact.head<2>()).norm(), 1e-6);
}

template <class Model>
void expect_transition_matches_central_differences() {
  const Model m;
  const NavState x = test::sample_nav_state();
  BodyIncrements u;
  const double dt = 0.01;
  u.dtheta = Eigen::Vector3d(0.002, -0.001, 0.004);
  u.dv = Eigen::Vector3d(0.03, -0.02, -0.097);
  SquareMatrix<15> F;
  const NavState y = m.predict(x, u, dt, &F);
  SquareMatrix<15> F_num;
  for (int i = 0; i < 15; ++i) {
    // Position rows are in metres of latitude in radians (ulp ~7e-10 m): steps of 1 cm and 1e-3
    // keep roundoff below 4e-7; truncation of the attitude columns ~h^2 = 1e-6 relative.
    const double h = i < 3 ? 1e-2 : 1e-3;
    Vector<15> ep = Vector<15>::Zero(), em = Vector<15>::Zero();
    ep(i) = h;
    em(i) = -h;
    F_num.col(i) = (m.difference(m.predict(m.inject(x, ep), u, dt, nullptr), y) -
                    m.difference(m.predict(m.inject(x, em), u, dt, nullptr), y)) /
                   (2.0 * h);
  }
  // F leaves out the gravity gradient (2 g / R dt ~ 3e-8 here) and the dependence of the earth
  // and transport rates on the position and velocity errors (below 1e-8 per step); the bound is
  // the differencing's own error above. Leaving out the full mechanisation's sculling term in
  // v-bg (5e-4 here) fails it.
  EXPECT_LT((F - F_num).cwiseAbs().maxCoeff(), 1.5e-6) << F - F_num;
}

TEST(Mechanisation, TransitionJacobianSimplified) { expect_transition_matches_central_differences<Simple>(); }
TEST(Mechanisation, TransitionJacobianFull) { expect_transition_matches_central_differences<Full>(); }

TEST(ImuInput, AppliesMountingAndDelayAndRefusesBadStamps) {
  ImuInput in;
  in.body_from_imu = mounting_rotation(180.0 * kDeg, 0.0, 0.0);  // IMU upside down
  in.delay_s = -0.125;
  messages::ImuSample s;
  s.t = 10.0;
  s.accel = Eigen::Vector3d(0.0, 0.0, 9.8);
  s.gyro = Eigen::Vector3d(0.0, 0.01, 0.02);
  BodyIncrements u;
  double dt = 0.0;
  EXPECT_EQ(in.next(s, u, dt).problem, Problem::time_not_set);  // the first sample starts the clock
  EXPECT_DOUBLE_EQ(in.apply_delay(s).t, 9.875);
  messages::ImuSample same = s;
  EXPECT_EQ(in.next(same, u, dt).problem, Problem::non_positive_dt);
  messages::ImuSample back = s;
  back.t = 9.9;
  EXPECT_EQ(in.next(back, u, dt).problem, Problem::out_of_order_time);
  messages::ImuSample nan = s;
  nan.t = std::nan("");
  EXPECT_EQ(in.next(nan, u, dt).problem, Problem::non_finite_dt);
  messages::ImuSample absurd = s;
  absurd.t = 10.01;
  absurd.gyro = Eigen::Vector3d(100.0, 0.0, 0.0);
  EXPECT_EQ(in.next(absurd, u, dt).problem, Problem::input_magnitude);
  // After the refusals the adapter is where it was: the next good sample gets dt from 10.0.
  messages::ImuSample next = s;
  next.t = 10.02;
  ASSERT_TRUE(in.next(next, u, dt).accepted());
  EXPECT_NEAR(dt, 0.02, 1e-15);
  EXPECT_FALSE(u.has_previous);
  EXPECT_LT((u.dv - Eigen::Vector3d(0.0, 0.0, -9.8 * 0.02)).norm(), 1e-14);    // z flipped
  EXPECT_LT((u.dtheta - Eigen::Vector3d(0.0, -0.01, -0.02) * 0.02).norm(), 1e-15);

  // Increments (the interval ending at the stamp) and rates (held from the stamp) agree for a
  // constant rate, and the previous increment is carried for coning and sculling.
  ImuInput inc = in;
  inc.restart();
  messages::ImuSample a = s, b = s;
  a.increments = b.increments = true;
  a.accel *= 0.01;
  a.gyro *= 0.01;
  b = a;
  b.t = 10.01;
  EXPECT_FALSE(inc.next(a, u, dt).accepted());
  ASSERT_TRUE(inc.next(b, u, dt).accepted());
  EXPECT_LT((u.dv - Eigen::Vector3d(0.0, 0.0, -0.098)).norm(), 1e-15);
  BodyIncrements r;
  ASSERT_TRUE(in.from_rates(s.gyro, s.accel, 0.01, r).accepted());
  EXPECT_TRUE(r.has_previous);
  EXPECT_LT((r.prev_dv - Eigen::Vector3d(0.0, 0.0, -9.8 * 0.02)).norm(), 1e-14);
  EXPECT_EQ(in.from_rates(s.gyro, s.accel, 0.0, r).problem, Problem::non_positive_dt);
}

}  // namespace

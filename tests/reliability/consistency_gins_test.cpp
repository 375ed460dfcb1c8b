// Monte Carlo consistency of the geodetic GNSS/INS error-state filter: the 15-state
// InsNavModel<FullStrapdown> (models/ins_nav.hpp: latitude/longitude/height, NED velocity,
// quaternion attitude, Gauss-Markov gyro and accelerometer biases; earth rate, transport rate,
// coning and sculling) with GnssGeodeticPosition fixes (models/ins_updates.hpp) through a
// lever arm, run by eskf::predict / eskf::update as tests/gins does.
//
// The truth is integrated with the model's own mechanisation from noise-free increments that
// follow a known motion (smooth body rate, smooth navigation-frame acceleration; the Coriolis
// and transport terms the increments do not cancel bend it by millimetres per second), its
// biases first-order Gauss-Markov processes of the model's density and correlation time. The
// filter reads those increments plus white noise of exactly the densities it assumes
// (standard deviation density x sqrt(dt) per increment), the fixes are the truth's antenna
// position plus white NED noise of the filter's R. 50 seeded runs of 60 s at 100 Hz, fixes at
// 1 Hz; the filter with its process noise halved (Q/2: every density divided by sqrt 2) must
// be rejected by the same check (consistency_report.hpp).
#include <gtest/gtest.h>

#include <cmath>

#include "consistency_report.hpp"
#include "ins_sim.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/models/ins_nav.hpp"
#include "ctxfuse/models/ins_updates.hpp"

// Named, not anonymous: the area's sources share one unity build (tests/CMakeLists.txt).
namespace consistency_gins {
using namespace ctxfuse;
using Model = models::InsNavModel<models::FullStrapdown>;
using State = Model::State;

constexpr int runs = 50, seconds = 60, imu_per_fix = 100;
constexpr double dt = 1.0 / imu_per_fix, fix_sigma = 0.1, deg = 3.14159265358979323846 / 180.0;

// Consumer-grade MEMS figures (as in the 15-state ESKF test): noisy enough that Q shapes the
// covariance between 1 Hz fixes. Bias correlation time 300 s.
Model imu_model(double q_factor) {
  const double s = std::sqrt(q_factor);  // every Q entry is a density squared
  Model m;
  m.gyro_noise_density = 2e-3 * s;            // rad/s/sqrt(Hz)
  m.accel_noise_density = 5e-2 * s;           // m/s^2/sqrt(Hz)
  m.gyro_bias = models::GaussMarkov{1e-4 * s, 300.0};   // rad/s/sqrt(s)
  m.accel_bias = models::GaussMarkov{1e-3 * s, 300.0};  // m/s^2/sqrt(s)
  return m;
}

Eigen::Vector3d true_rate(double t) { return {0.05 * std::sin(0.3 * t), 0.04 * std::cos(0.2 * t), 0.15 * std::sin(0.1 * t)}; }
Eigen::Vector3d true_accel_n(double t) { return {0.6 * std::sin(0.2 * t), 0.5 * std::cos(0.15 * t), 0.1 * std::sin(0.5 * t)}; }

reliability::Verdict monte_carlo(double q_factor) {
  const Model truth_model = imu_model(1.0);
  const Model filter_model = imu_model(q_factor);
  models::GnssGeodeticPosition<State> fix;
  fix.lever_arm = Eigen::Vector3d(0.5, 0.0, -1.0);  // antenna forward and above the IMU
  Vector<15> prior_sd;
  prior_sd << 1.0, 1.0, 1.0, 0.1, 0.1, 0.1, 0.01, 0.01, 0.03, 1e-3, 1e-3, 1e-3, 0.02, 0.02, 0.02;

  eval::MonteCarloAverage nees(seconds), nis(seconds);
  for (int r = 0; r < runs; ++r) {
    sim::Rng rng(20261205u + static_cast<std::uint64_t>(r));
    eskf::Belief<Model> b;
    b.nominal.get<"p">() = Eigen::Vector3d(48.1 * deg, 11.6 * deg, 520.0);
    b.nominal.get<"v">() = Eigen::Vector3d(5.0, 2.0, 0.0);
    b.nominal.get<"theta">() = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()));
    b.cov = prior_sd.cwiseAbs2().asDiagonal();
    Vector<15> draw;
    for (int i = 0; i < 15; ++i) draw(i) = prior_sd(i) * rng.normal();
    State truth = truth_model.inject(b.nominal, draw);  // the first error is N(0, P0)

    const double sg = truth_model.gyro_noise_density * std::sqrt(dt), sa = truth_model.accel_noise_density * std::sqrt(dt);
    models::BodyIncrements clean_prev, measured_prev;
    for (int k = 0; k < seconds * imu_per_fix; ++k) {
      const double t = k * dt;
      const Eigen::Vector3d& llh = truth.get<"p">();
      const Eigen::Vector3d g(0.0, 0.0, earth::normal_gravity(llh(0), llh(2)));
      models::BodyIncrements clean;
      clean.dtheta = (true_rate(t) + truth.get<"bg">()) * dt;
      clean.dv = truth.get<"theta">().conjugate() * ((true_accel_n(t) - g) * dt) + truth.get<"ba">() * dt;
      models::BodyIncrements measured = clean;
      measured.dtheta += sg * rng.normals<3>();
      measured.dv += sa * rng.normals<3>();
      reliability::chain(clean, clean_prev, k == 0);
      reliability::chain(measured, measured_prev, k == 0);
      truth = truth_model.predict(truth, clean, dt, nullptr);
      reliability::walk_biases(truth_model, truth, dt, rng);
      EXPECT_TRUE(eskf::predict(filter_model, b, measured, dt).accepted());

      if ((k + 1) % imu_per_fix != 0) continue;
      const auto epoch = static_cast<std::size_t>((k + 1) / imu_per_fix - 1);
      const Eigen::Vector3d antenna = fix.predict(truth, nullptr);
      const Vector<3> z = earth::GeodeticRetraction::inject(antenna, fix_sigma * rng.normals<3>());
      fix.R = models::geodetic_position_noise(z, Eigen::Matrix3d::Identity() * fix_sigma * fix_sigma);
      const Status s = eskf::update(filter_model, fix, b, z);
      EXPECT_TRUE(s.accepted());
      nis.add(epoch, s.nis);
      nees.add(epoch, eval::nees<15>(truth_model.difference(truth, b.nominal), b.cov));
    }
  }
  return {eval::check_bands(nees, 15, runs), eval::check_bands(nis, 3, runs)};
}

TEST(GinsConsistency, MatchedNoiseIsConsistent) {
  const auto v = monte_carlo(1.0);
  reliability::print_verdict("gins_ins15_full_gnss", v);
  EXPECT_TRUE(v.consistent());
}

TEST(GinsConsistency, HalvedProcessNoiseIsRejected) {
  const auto v = monte_carlo(0.5);
  reliability::print_verdict("gins_ins15_full_gnss_half_q", v);
  EXPECT_FALSE(v.consistent());
}

}  // namespace consistency_gins

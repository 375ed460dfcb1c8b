// Monte Carlo consistency of the error-state EKF with the 15-state INS (models/ins.hpp) and
// GNSS position fixes with a lever arm. The truth is a known trajectory: its angular rate and
// navigation-frame acceleration are smooth functions of time, its IMU biases random walks of
// the model's densities. The IMU the filter reads is the truth's (biases included) plus white
// noise of exactly the densities the filter assumes (standard deviation density / sqrt(dt) per
// sample), the fixes are the truth's antenna position plus white noise of the filter's R. The
// truth is integrated with the model's own mechanisation from the noise-free samples, so the
// only model error left is the linearisation. 50 seeded runs of 60 s at 100 Hz, fixes at 1 Hz.
#include <gtest/gtest.h>

#include <cmath>

#include "consistency_report.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/models/ins.hpp"

// Named, not anonymous: the area's sources share one unity build (tests/CMakeLists.txt).
namespace consistency_eskf {
using namespace ctxfuse;
using models::Ins15Model;
using L = models::Ins15Layout;

// 50 runs, the minimum: this is the costliest Monte Carlo here (most of all in the
// sanitizer build, about 40 s per test at 100 runs).
constexpr int runs = 50, seconds = 60, imu_per_fix = 100;
constexpr double dt = 1.0 / imu_per_fix, fix_sigma = 0.1;

// A consumer-grade MEMS IMU, noisy enough that the process noise shapes the covariance
// between 1 Hz fixes (with a far better IMU the fixes alone would set it, and halving Q would
// change little that a test could see).
Ins15Model imu_model() {
  Ins15Model m;
  m.gyro_noise_density = 2e-3;   // rad/s/sqrt(Hz)
  m.accel_noise_density = 5e-2;  // m/s^2/sqrt(Hz)
  m.gyro_bias.density = 1e-4;    // rad/s/sqrt(s)
  m.accel_bias.density = 1e-3;   // m/s^2/sqrt(s)
  return m;
}

Ins15Model scaled(Ins15Model m, double q_factor) {
  const double s = std::sqrt(q_factor);  // every Q entry is a density squared
  m.gyro_noise_density *= s;
  m.accel_noise_density *= s;
  m.gyro_bias.density *= s;
  m.accel_bias.density *= s;
  return m;
}

// The known motion: body angular rate and navigation-frame acceleration at time t.
Eigen::Vector3d true_rate(double t) { return {0.05 * std::sin(0.3 * t), 0.04 * std::cos(0.2 * t), 0.15 * std::sin(0.1 * t)}; }
Eigen::Vector3d true_accel_n(double t) { return {0.6 * std::sin(0.2 * t), 0.5 * std::cos(0.15 * t), 0.1 * std::sin(0.5 * t)}; }

reliability::Verdict monte_carlo(double q_factor) {
  const Ins15Model truth_model = imu_model();
  const Ins15Model filter_model = scaled(truth_model, q_factor);
  models::GnssPosition<> fix;
  fix.lever_arm = Eigen::Vector3d(0.5, 0.0, 1.0);
  fix.R = SquareMatrix<3>::Identity() * fix_sigma * fix_sigma;
  Vector<15> prior_sd;
  prior_sd << 1.0, 1.0, 1.0, 0.1, 0.1, 0.1, 0.01, 0.01, 0.03, 1e-3, 1e-3, 1e-3, 0.02, 0.02, 0.02;

  eval::MonteCarloAverage nees(seconds), nis(seconds);
  for (int r = 0; r < runs; ++r) {
    sim::Rng rng(20261202u + static_cast<std::uint64_t>(r));
    eskf::Belief<Ins15Model> prior;
    prior.nominal.v = Eigen::Vector3d(5.0, 0.0, 0.0);
    prior.cov = prior_sd.cwiseProduct(prior_sd).asDiagonal();
    Vector<15> draw;
    for (int i = 0; i < 15; ++i) draw(i) = prior_sd(i) * rng.normal();
    models::InsState truth = truth_model.inject(prior.nominal, draw);  // the first error is N(0, P0)
    Eskf<Ins15Model> f(filter_model, prior);

    const double sg = truth_model.gyro_noise_density / std::sqrt(dt), sa = truth_model.accel_noise_density / std::sqrt(dt);
    const double sbg = std::sqrt(truth_model.gyro_bias.variance(dt)), sba = std::sqrt(truth_model.accel_bias.variance(dt));
    for (int k = 0; k < seconds * imu_per_fix; ++k) {
      const double t = k * dt;
      // The sample that makes the truth's own mechanisation follow the known motion.
      models::ImuSample clean;
      clean.gyro = true_rate(t) + truth.bg;
      clean.accel = truth.q.conjugate() * (true_accel_n(t) - truth_model.gravity) + truth.ba;
      models::ImuSample measured = clean;
      measured.gyro += sg * rng.normals<3>();
      measured.accel += sa * rng.normals<3>();
      truth = truth_model.predict(truth, clean, dt, nullptr);
      truth.bg += sbg * rng.normals<3>();
      truth.ba += sba * rng.normals<3>();
      EXPECT_TRUE(f.predict(measured, dt).accepted());

      if ((k + 1) % imu_per_fix != 0) continue;
      const auto epoch = static_cast<std::size_t>((k + 1) / imu_per_fix - 1);
      const Vector<3> z = fix.predict(truth, nullptr) + fix_sigma * rng.normals<3>();
      const Status s = f.update(fix, z);
      EXPECT_TRUE(s.accepted());
      nis.add(epoch, s.nis);
      nees.add(epoch, eval::nees<15>(truth_model.difference(truth, f.nominal()), f.belief().cov));
    }
  }
  return {eval::check_bands(nees, 15, runs), eval::check_bands(nis, 3, runs)};
}

TEST(EskfConsistency, MatchedNoiseIsConsistent) {
  const auto v = monte_carlo(1.0);
  reliability::print_verdict("eskf_ins15_gnss", v);
  EXPECT_TRUE(v.consistent());
}

TEST(EskfConsistency, HalvedProcessNoiseIsRejected) {
  const auto v = monte_carlo(0.5);
  reliability::print_verdict("eskf_ins15_gnss_half_q", v);
  EXPECT_FALSE(v.consistent());
}

}  // namespace consistency_eskf

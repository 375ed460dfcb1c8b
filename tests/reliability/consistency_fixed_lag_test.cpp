// Monte Carlo consistency of the fixed-lag smoother (filters/fixed_lag.hpp) on the EKF test's
// problem: a planar constant-velocity target (white acceleration noise, the model's own
// discrete Q) ranged by three anchors with white noise of the model's sigma, the truth drawn
// from the smoother's prior. 100 seeded runs of 200 epochs, window K = 5.
//
// What is checked, with the check of consistency_report.hpp:
//  - NEES of the newest state against its marginal covariance (newest_covariance(), the last
//    Schur complement of the window's normal equations at the solution): the smoother's
//    promise about its output.
//  - NIS of the one-step prediction from the newest belief: the three ranges stacked,
//    y = z - h(F x), S = H (F P F' + Q) H' + R with H the ranges' Jacobian at F x, written out
//    here (the smoother has no innovation of its own). chi-square(3) to first order, as the
//    EKF's sum of sequential NIS is.
// The smoother with its process noise halved (Q/2 in its motion model and in that prediction,
// Q in the truth) must be rejected by the same check.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <array>
#include <memory>

#include "consistency_report.hpp"
#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/filters/fixed_lag.hpp"
#include "ctxfuse/models/kinematic.hpp"

// Named, not anonymous: the area's sources share one unity build (tests/CMakeLists.txt).
namespace consistency_fixed_lag {
using namespace ctxfuse;
using L = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;
using Cv = models::ConstantVelocity<L, 2>;
using Range = models::RangeToPoint<L, 2>;
constexpr int K = 5, anchors = 3;
using Smoother = FixedLagSmoother<Cv, Range, K, anchors>;

constexpr int runs = 100, epochs = 200;
constexpr double dt = 0.1, accel_psd = 1.0, range_sigma = 0.1;

/// The stacked NIS of the ranges z at the prediction of `belief` over dt by `motion`.
double prediction_nis(const Cv& motion, const Gaussian<4>& belief, const std::array<Range, anchors>& ranges,
                      const Vector<anchors>& z) {
  SquareMatrix<4> F;
  const Vector<4> x = motion.predict(belief.mean, {}, dt, &F);
  const SquareMatrix<4> P = F * belief.cov * F.transpose() + motion.noise(x, {}, dt);
  Matrix<anchors, 4> H;
  Vector<anchors> y;
  for (int i = 0; i < anchors; ++i) {
    Matrix<1, 4> Hi;
    y(i) = z(i) - ranges[static_cast<std::size_t>(i)].predict(x, &Hi)(0);
    H.row(i) = Hi;
  }
  const SquareMatrix<anchors> S =
      H * P * H.transpose() + SquareMatrix<anchors>::Identity() * range_sigma * range_sigma;
  return y.dot(Eigen::LLT<SquareMatrix<anchors>>(S).solve(y));
}

reliability::Verdict monte_carlo(double filter_psd_factor) {
  Cv truth;
  truth.accel_psd = accel_psd;
  Cv assumed = truth;
  assumed.accel_psd *= filter_psd_factor;
  std::array<Range, anchors> ranges;
  const Vector<2> where[anchors] = {{-30.0, 0.0}, {30.0, 0.0}, {0.0, 40.0}};
  for (int i = 0; i < anchors; ++i) {
    ranges[static_cast<std::size_t>(i)].anchor = where[i];
    ranges[static_cast<std::size_t>(i)].sigma = range_sigma;
  }
  const SquareMatrix<4> Q_chol = Eigen::LLT<SquareMatrix<4>>(truth.noise(Vector<4>::Zero(), {}, dt)).matrixL();
  const Vector<4> prior_sd(0.5, 0.5, 0.3, 0.3);

  // The smoother holds two windows and two systems by value: on the heap, as its header says.
  auto smoother = std::make_unique<Smoother>(assumed);
  eval::MonteCarloAverage nees(epochs), nis(epochs);
  for (int r = 0; r < runs; ++r) {
    sim::Rng rng(20261204u + static_cast<std::uint64_t>(r));
    auto normal4 = [&] { return rng.normals<4>(); };
    const auto start = test::draw_start(Vector<4>(0.0, 5.0, 1.0, 0.5), prior_sd, rng);
    Vector<4> x = start.truth;
    EXPECT_TRUE(smoother->initialise(0.0, start.prior).accepted());
    for (int k = 0; k < epochs; ++k) {
      x = truth.predict(x, {}, dt, nullptr) + Q_chol * normal4();
      Smoother::Measurements m;
      Vector<anchors> z;
      for (int i = 0; i < anchors; ++i) {
        const Range& h = ranges[static_cast<std::size_t>(i)];
        z(i) = (L::get<"p">(x) - h.anchor).norm() + range_sigma * rng.normal();
        m.add(h, Vector<1>(z(i)));
      }
      nis.add(static_cast<std::size_t>(k), prediction_nis(assumed, smoother->newest_belief(), ranges, z));
      EXPECT_TRUE(smoother->step(dt * (k + 1), {}, m).accepted()) << "run " << r << " epoch " << k;
      nees.add(static_cast<std::size_t>(k), eval::nees<4>(x - smoother->newest(), smoother->newest_covariance()));
    }
  }
  return {eval::check_bands(nees, 4, runs), eval::check_bands(nis, anchors, runs)};
}

TEST(FixedLagConsistency, MatchedNoiseIsConsistent) {
  const auto v = monte_carlo(1.0);
  reliability::print_verdict("fixed_lag_cv_ranges", v);
  EXPECT_TRUE(v.consistent());
}

TEST(FixedLagConsistency, HalvedProcessNoiseIsRejected) {
  const auto v = monte_carlo(0.5);
  reliability::print_verdict("fixed_lag_cv_ranges_half_q", v);
  EXPECT_FALSE(v.consistent());
}

}  // namespace consistency_fixed_lag

// Monte Carlo consistency (NEES / NIS) against chi-square tables and against a filter whose
// model is exactly the simulated one: a textbook-consistent Kalman filter must stay inside the
// band, and the same filter with its process noise under-stated must leave it.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <cmath>
#include <cstdio>
#include <limits>

#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/eval/consistency.hpp"
#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/sim/random.hpp"
#include "support/draw_start.hpp"

namespace {
using namespace ctxfuse;
using L = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;
using Cv = models::ConstantVelocity<L, 2>;
using PositionFix = models::BlockObservation<L, "p">;

TEST(Consistency, NeesByHand) {
  Vector<2> e(1.0, 2.0);
  SquareMatrix<2> P;
  P << 1.0, 0.0, 0.0, 4.0;
  EXPECT_DOUBLE_EQ(eval::nees<2>(e, P), 2.0);
  P << 2.0, 1.0, 1.0, 2.0;  // inverse (1/3) [2 -1; -1 2]: e' P^-1 e = (2 - 4 + 8) / 3
  EXPECT_NEAR(eval::nees<2>(e, P), 2.0, 1e-15);
  P << 1.0, 2.0, 2.0, 1.0;  // indefinite
  EXPECT_TRUE(std::isnan(eval::nees<2>(e, P)));
  P.setIdentity();
  e(0) = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(std::isnan(eval::nees<2>(e, P)));
}

TEST(Consistency, BandFromChiSquareTables) {
  // chi-square(100) quantiles from printed tables: 0.025 -> 74.222, 0.975 -> 129.561.
  const auto band = eval::average_chi_square_band(2, 50, 0.95);
  EXPECT_NEAR(band.lower, 74.222 / 50.0, 1e-4);
  EXPECT_NEAR(band.upper, 129.561 / 50.0, 1e-4);
  EXPECT_TRUE(band.contains(2.0));
  EXPECT_FALSE(band.contains(2.7));
  EXPECT_THROW((void)eval::average_chi_square_band(0, 10), std::invalid_argument);
  EXPECT_THROW((void)eval::average_chi_square_band(2, 10, 1.0), std::invalid_argument);
}

struct Outcome {
  eval::MonteCarloAverage nees, nis;
  Outcome(std::size_t steps) : nees(steps), nis(steps) {}
};

// `runs` independent runs of a CV target with position fixes; the filter assumes
// `assumed_psd` while the truth moves with `true_psd`.
Outcome monte_carlo(int runs, int steps, double true_psd, double assumed_psd) {
  const double dt = 0.1, fix_sigma = 0.25;
  Cv truth_model;
  truth_model.accel_psd = true_psd;
  Cv filter_model;
  filter_model.accel_psd = assumed_psd;
  PositionFix fix;
  fix.R = SquareMatrix<2>::Identity() * fix_sigma * fix_sigma;
  const SquareMatrix<4> Q_true = truth_model.noise(Vector<4>::Zero(), {}, dt);
  const SquareMatrix<4> Q_chol = Eigen::LLT<SquareMatrix<4>>(Q_true).matrixL();
  Vector<4> prior_sd(1.0, 1.0, 0.5, 0.5);

  Outcome out(static_cast<std::size_t>(steps));
  sim::Rng rng(20261123);
  auto normal4 = [&] { return rng.normals<4>(); };
  for (int r = 0; r < runs; ++r) {
    const auto start = test::draw_start(Vector<4>(0.0, 0.0, 1.0, -0.5), prior_sd, rng);
    Vector<4> x = start.truth;
    Ekf<Cv> f(filter_model, start.prior);
    for (int k = 0; k < steps; ++k) {
      x = truth_model.predict(x, {}, dt, nullptr) + Q_chol * normal4();
      EXPECT_TRUE(f.predict({}, dt).accepted());
      const Vector<2> z = L::get<"p">(x) + fix_sigma * rng.normals<2>();
      const auto status = f.update(fix, z);
      EXPECT_TRUE(status.accepted());
      out.nis.add(static_cast<std::size_t>(k), status.nis);
      out.nees.add(static_cast<std::size_t>(k), eval::nees<4>(x - f.belief().mean, f.belief().cov));
    }
  }
  return out;
}

TEST(Consistency, MatchedKalmanFilterStaysInsideTheBand) {
  constexpr int runs = 100, steps = 200;
  const auto out = monte_carlo(runs, steps, 0.5, 0.5);
  EXPECT_EQ(out.nees.failures(), 0u);
  const auto nees_band = eval::average_chi_square_band(4, runs, 0.95);
  const auto nis_band = eval::average_chi_square_band(2, runs, 0.95);
  std::printf("matched: NEES inside %.3f, NIS inside %.3f, NEES average %.3f, NIS average %.3f\n",
              out.nees.fraction_inside(nees_band), out.nis.fraction_inside(nis_band), out.nees.overall_average(),
              out.nis.overall_average());
  // 95 % of the steps expected inside; the steps are correlated, so allow some slack.
  EXPECT_GT(out.nees.fraction_inside(nees_band), 0.88);
  EXPECT_GT(out.nis.fraction_inside(nis_band), 0.88);
  EXPECT_NEAR(out.nees.overall_average(), 4.0, 0.3);
  EXPECT_NEAR(out.nis.overall_average(), 2.0, 0.15);
}

TEST(Consistency, UnderstatedProcessNoiseLeavesTheBand) {
  constexpr int runs = 100, steps = 200;
  const auto out = monte_carlo(runs, steps, 0.5, 0.025);  // the filter believes 20x less
  const auto nees_band = eval::average_chi_square_band(4, runs, 0.95);
  std::printf("understated: NEES inside %.3f, NEES average %.3f\n", out.nees.fraction_inside(nees_band),
              out.nees.overall_average());
  EXPECT_LT(out.nees.fraction_inside(nees_band), 0.2);
  EXPECT_GT(out.nees.overall_average(), 6.0);
}

}  // namespace

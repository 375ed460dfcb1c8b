// PSO on test functions with known optima (sphere, Rosenbrock, Rastrigin), determinism for a
// seed, bounds respected, maximisation.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "ctxfuse/classify/pso.hpp"

namespace {

using namespace ctxfuse::classify;

TEST(Pso, SphereMinimumAtShiftedCentre) {
  const Eigen::Vector3d centre(1.5, -2.0, 0.25);
  const auto f = [&](const Eigen::Vector3d& x) { return (x - centre).squaredNorm(); };
  PsoOptions o;
  o.swarm_size = 20;
  o.iterations = 150;
  const auto r = pso_minimize<3>(f, Eigen::Vector3d::Constant(-5), Eigen::Vector3d::Constant(5), o);
  EXPECT_LT((r.best_position - centre).norm(), 1e-4);
  EXPECT_LT(r.best_value, 1e-8);
  EXPECT_EQ(r.evaluations, 20 * 151);
}

TEST(Pso, RosenbrockValley) {
  const auto f = [](const Eigen::Vector2d& x) { return 100.0 * std::pow(x[1] - x[0] * x[0], 2) + std::pow(1.0 - x[0], 2); };
  PsoOptions o;
  o.swarm_size = 30;
  o.iterations = 400;
  const auto r = pso_minimize<2>(f, Eigen::Vector2d(-2, -1), Eigen::Vector2d(2, 3), o);
  EXPECT_NEAR(r.best_position[0], 1.0, 1e-2);
  EXPECT_NEAR(r.best_position[1], 1.0, 2e-2);
  EXPECT_LT(r.best_value, 1e-4);
}

TEST(Pso, RastriginGlobalMinimumAmongManyLocalOnes) {
  const auto f = [](const Eigen::Vector2d& x) {
    double s = 20.0;
    for (int i = 0; i < 2; ++i) s += x[i] * x[i] - 10.0 * std::cos(2.0 * std::numbers::pi * x[i]);
    return s;
  };
  PsoOptions o;
  o.swarm_size = 40;
  o.iterations = 200;
  o.inertia = 0.9;
  o.final_inertia = 0.4;
  int found = 0;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    o.seed = seed;
    const auto r = pso_minimize<2>(f, Eigen::Vector2d::Constant(-5.12), Eigen::Vector2d::Constant(5.12), o);
    // Local minima sit near integer points with value >= ~1; the global one is 0 at the origin.
    if (r.best_value < 1e-3 && r.best_position.norm() < 1e-2) ++found;
  }
  EXPECT_GE(found, 4);
}

TEST(Pso, DeterministicForSeedAndRespectsBounds) {
  const auto f = [](const Eigen::Vector2d& x) { return std::sin(3 * x[0]) * std::cos(2 * x[1]) + 0.1 * x.squaredNorm(); };
  PsoOptions o;
  o.seed = 42;
  const Eigen::Vector2d lo(-1, 0.5), hi(2, 3);
  int outside = 0;
  const auto g = [&](const Eigen::Vector2d& x) {
    if ((x.array() < lo.array()).any() || (x.array() > hi.array()).any()) ++outside;
    return f(x);
  };
  const auto a = pso_minimize<2>(g, lo, hi, o);
  const auto b = pso_minimize<2>(g, lo, hi, o);
  EXPECT_EQ(a.best_position, b.best_position);
  EXPECT_EQ(a.best_value, b.best_value);
  EXPECT_EQ(outside, 0);
  o.seed = 43;
  const auto c = pso_minimize<2>(g, lo, hi, o);
  EXPECT_NE(a.best_position, c.best_position);
}

TEST(Pso, MaximiseFindsPeakAndReportsMaximum) {
  const auto f = [](const Eigen::Matrix<double, 1, 1>& x) { return 3.0 - (x[0] - 0.7) * (x[0] - 0.7); };
  const auto r = pso_maximize<1>(f, Eigen::Matrix<double, 1, 1>(-4), Eigen::Matrix<double, 1, 1>(4));
  EXPECT_NEAR(r.best_position[0], 0.7, 1e-3);
  EXPECT_NEAR(r.best_value, 3.0, 1e-6);
}

TEST(Pso, RejectsBadOptions) {
  const auto f = [](const Eigen::Vector2d& x) { return x.sum(); };
  PsoOptions o;
  o.swarm_size = 0;
  EXPECT_THROW(pso_minimize<2>(f, Eigen::Vector2d::Zero(), Eigen::Vector2d::Ones(), o), std::invalid_argument);
  EXPECT_THROW(pso_minimize<2>(f, Eigen::Vector2d::Ones(), Eigen::Vector2d::Zero()), std::invalid_argument);
}

}  // namespace

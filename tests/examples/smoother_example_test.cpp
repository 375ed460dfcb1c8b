// examples/smoother.hpp against the whole run solved by hand: the fixed-lag smoother's window
// minimises the same sum of squares as a dense Gauss-Newton over every state from t = 0 (prior,
// motion and measurement terms, written out here with plain Eigen), exactly while nothing has
// been marginalised, and through marginalisation when the measurement is linear.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "smoother.hpp"

namespace {
using namespace ctxfuse;
namespace se = smoother_example;
using Mat = Eigen::MatrixXd;
using Vec = Eigen::VectorXd;

/// e(X) of one measurement at state x: predicted minus observed, wrapped as the model wraps it.
template <class Meas>
Vec meas_error(const Meas& m, const Vector<4>& x, const Vector<Meas::dim>& z, Mat& H) {
  Matrix<Meas::dim, 4> h;
  const Vector<Meas::dim> zp = m.predict(x, &h);
  H = h;
  if constexpr (requires { m.residual(z, zp); })
    return -m.residual(z, zp);
  else
    return zp - z;
}

/// Minimises |x0 - m0|^2_P0^-1 + sum_k |x_k - F x_(k-1)|^2_Q^-1 + sum_k |e_k(x_k)|^2_R^-1 over
/// all states by Gauss-Newton on the dense normal equations, from `start`, until no element
/// of the step exceeds 1e-12. Returns the states.
template <class Meas>
std::vector<Vector<4>> batch(const se::ConstantVelocity& model, const Gaussian<4>& prior, double dt, const Meas& sensor,
                             const std::vector<Vector<Meas::dim>>& z, std::vector<Vector<4>> x) {
  const int n = static_cast<int>(x.size());  // states 0..n-1; z[k-1] observes state k
  SquareMatrix<4> F;
  (void)model.predict(Vector<4>::Zero(), {}, dt, &F);
  const Mat Wq = model.noise(Vector<4>::Zero(), {}, dt).inverse();
  const Mat Wp = prior.cov.inverse();
  const Mat Wr = sensor.noise(x[0]).inverse();
  for (int it = 0; it < 50; ++it) {
    Mat A = Mat::Zero(4 * n, 4 * n);
    Vec b = Vec::Zero(4 * n);
    auto add = [&](const Mat& J, int block_a, const Mat& Ja, int block_b, const Vec& e, const Mat& W) {
      // A term e with Jacobian J on block_a (and Ja on block_b when block_b >= 0).
      A.block(4 * block_a, 4 * block_a, 4, 4) += J.transpose() * W * J;
      b.segment(4 * block_a, 4) -= J.transpose() * W * e;
      if (block_b >= 0) {
        A.block(4 * block_b, 4 * block_b, 4, 4) += Ja.transpose() * W * Ja;
        A.block(4 * block_a, 4 * block_b, 4, 4) += J.transpose() * W * Ja;
        A.block(4 * block_b, 4 * block_a, 4, 4) += Ja.transpose() * W * J;
        b.segment(4 * block_b, 4) -= Ja.transpose() * W * e;
      }
    };
    const Mat I = Mat::Identity(4, 4);
    add(I, 0, Mat(), -1, x[0] - prior.mean, Wp);
    for (int k = 1; k < n; ++k) {
      const auto i = static_cast<std::size_t>(k);
      add(I, k, -F, k - 1, x[i] - F * x[i - 1], Wq);
      Mat H;
      const Vec e = meas_error(sensor, x[i], z[i - 1], H);
      add(H, k, Mat(), -1, e, Wr);
    }
    const Vec dx = A.ldlt().solve(b);
    for (int k = 0; k < n; ++k) x[static_cast<std::size_t>(k)] += dx.segment(4 * k, 4);
    if (dx.cwiseAbs().maxCoeff() < 1e-12) return x;
  }
  ADD_FAILURE() << "the hand-written Gauss-Newton did not converge";
  return x;
}

/// Largest difference between a step's window and the batch states of the same epochs.
template <class StepT>
double window_gap(const StepT& step, const std::vector<Vector<4>>& states, double dt) {
  double gap = 0.0;
  for (int i = 0; i < step.window_size; ++i) {
    const auto w = static_cast<std::size_t>(i);
    const auto index = static_cast<std::size_t>(std::lround(step.times[w] / dt));
    gap = std::max(gap, (step.window[w] - states[index]).cwiseAbs().maxCoeff());
  }
  return gap;
}

TEST(SmootherExample, WindowIsTheWholeRunsGaussNewtonSolutionUntilItSlides) {
  // Range and bearing are nonlinear: until the first state is marginalised the window is the
  // whole run, so its states must be the minimum of the whole run's cost.
  se::Settings s;
  s.options.step_tolerance = 1e-10;  // converged to rounding, as the batch below
  const se::Run r = se::run(s);
  std::vector<Vector<2>> z;
  std::vector<Vector<4>> start{r.initial.mean};
  for (int k = 0; k < se::kLag - 1; ++k) {
    const auto& step = r.steps[static_cast<std::size_t>(k)];
    ASSERT_TRUE(step.smoothed) << k;
    z.push_back(step.z);
    start.push_back(step.ekf.mean);  // the batch starts from the EKF's path, not the smoother's
    const auto states = batch(r.model, r.initial, s.dt, r.sensor, z, start);
    EXPECT_EQ(step.window_size, k + 2);
    const double gap = window_gap(step, states, s.dt);
    std::printf("epochs 0-%d: largest gap to the batch %.2e\n", k + 1, gap);
    EXPECT_LT(gap, 1e-8) << "after step " << k + 1;
  }
}

/// A position fix: z = p + noise. Linear, so marginalisation loses nothing.
struct PositionFix {
  static constexpr int dim = 2;
  double sigma = 0.5;
  Vector<2> predict(const Vector<4>& x, Matrix<2, 4>* H) const {
    if (H) *H << 1, 0, 0, 0, 0, 1, 0, 0;
    return x.head<2>();
  }
  SquareMatrix<2> noise(const Vector<4>&) const { return SquareMatrix<2>::Identity() * sigma * sigma; }
};

TEST(SmootherExample, LinearWindowIsTheWholeRunsSolutionThroughMarginalisation) {
  // With a linear measurement the marginalised prior is exact: at every step, after many
  // slides, the window holds the whole run's least-squares states of its epochs.
  const se::Run r = se::run();  // its model, prior, times and truth
  PositionFix fix;
  using LinearSmoother = FixedLagSmoother<se::ConstantVelocity, PositionFix, se::kLag, 1>;
  auto smoother = std::make_unique<LinearSmoother>(r.model);
  ASSERT_TRUE(smoother->initialise(0.0, r.initial));
  sim::Rng rng(7);
  std::vector<Vector<2>> z;
  std::vector<Vector<4>> start{r.initial.mean};
  double largest = 0.0;
  for (const auto& step : r.steps) {
    const double nx = rng.normal(), ny = rng.normal();  // in this order
    z.push_back(step.truth.head<2>() + Vector<2>(nx, ny) * fix.sigma);
    LinearSmoother::Measurements m;
    m.add(fix, z.back());
    ASSERT_TRUE(smoother->step(step.t, {}, m));
    start.push_back(step.truth);  // a linear problem: one Gauss-Newton step from anywhere
    const auto states = batch(r.model, r.initial, r.settings.dt, fix, z, start);
    se::Step window;  // the smoother's window in the example's record
    se::record_window(*smoother, window);
    largest = std::max(largest, window_gap(window, states, r.settings.dt));
  }
  EXPECT_EQ(smoother->window().size, se::kLag);
  std::printf("30 steps, window of %d: largest gap to the whole run's solution %.2e\n", se::kLag, largest);
  EXPECT_LT(largest, 1e-9);
}

TEST(SmootherExample, EveryStepIsAcceptedAndTheLaggedEstimateIsTheOldestInTheWindow) {
  const se::Run r = se::run();
  ASSERT_EQ(r.steps.size(), 30u);
  for (std::size_t k = 0; k < r.steps.size(); ++k) {
    ASSERT_TRUE(r.steps[k].smoothed) << k;
    EXPECT_EQ(r.steps[k].window_size, std::min<int>(static_cast<int>(k) + 2, se::kLag));
    if (k + se::kLag - 1 < r.steps.size()) {  // epoch k's lagged estimate is K-1 steps later
      EXPECT_DOUBLE_EQ(r.steps[k + se::kLag - 1].times[0], r.steps[k].t);
    }
  }
}

}  // namespace

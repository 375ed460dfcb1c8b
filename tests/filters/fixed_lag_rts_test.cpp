// The fixed-lag RTS mean smoother (filters/fixed_lag_rts.hpp) against the textbook RTS written
// plainly over the same EKF run: C_k = P_k Phi_k' Pbar_{k+1}^-1 and
// xs_k = x_k + C_k (xs_{k+1} - xbar_{k+1}), with dense inverses and every record kept. The run
// has several predictions between updates (composed transitions), two updates at one time (one
// record), a held state (zero variance, zero noise) and runs longer than the ring.
#include <gtest/gtest.h>

#include <Eigen/LU>

#include <vector>

#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/fixed_lag_rts.hpp"
#include "ctxfuse/models/linear.hpp"
#include "ctxfuse/sim/random.hpp"

namespace {
using namespace ctxfuse;

// Position, velocity, a random-constant bias seen by one of the sensors, and a held state.
constexpr int N = 4;
using Process = models::LinearProcess<N, 0>;
using Sensor = models::LinearMeasurement<1, N>;

struct Epoch {  // what the textbook needs of each record
  double t = 0.0;
  Vector<N> prior_mean, mean;
  SquareMatrix<N> prior_cov, cov, phi;  // phi: from the epoch before to this prior
};

Process cv(double dt) {
  Process m;
  m.F.setIdentity();
  m.F(0, 1) = dt;
  const double q = 0.5;
  m.Q.setZero();
  m.Q(0, 0) = q * dt * dt * dt / 3.0;
  m.Q(0, 1) = m.Q(1, 0) = q * dt * dt / 2.0;
  m.Q(1, 1) = q * dt;
  return m;
}

/// An EKF run of `epochs` epochs into the fixed-lag smoother and into the list of epochs.
std::vector<Epoch> run(int epochs, FixedLagRts<N>& lag, std::uint64_t seed) {
  sim::Rng rng(seed);
  Gaussian<N> belief;
  belief.mean << 0.0, 1.0, 0.0, 2.0;
  belief.cov = Vector<N>(1.0, 0.5, 0.04, 0.0).asDiagonal();  // the last state is held
  double t = 0.0, truth_p = 0.0, truth_v = 1.0;
  const double truth_b = 0.15;
  lag.start(t, belief);
  std::vector<Epoch> out{{t, belief.mean, belief.mean, belief.cov, belief.cov, SquareMatrix<N>::Identity()}};
  for (int k = 0; k < epochs; ++k) {
    SquareMatrix<N> phi = SquareMatrix<N>::Identity();
    const int steps = 1 + k % 3;
    for (int j = 0; j < steps; ++j) {
      const double dt = 0.05 + 0.03 * j;
      SquareMatrix<N> F;
      EXPECT_TRUE(ekf::predict(cv(dt), belief, NoInput{}, dt, FilterOptions{}, &F).accepted());
      lag.predicted(F);
      phi = F * phi;
      t += dt;
      truth_p += truth_v * dt;
      truth_v += 0.2 * rng.normal() * std::sqrt(dt);
    }
    const Gaussian<N> prior = belief;
    Sensor position;
    position.H << 1.0, 0.0, 0.0, 0.0;
    position.R << 0.01;
    EXPECT_TRUE(ekf::update<N>(position, belief, Vector<1>(truth_p + 0.1 * rng.normal())).accepted());
    EXPECT_TRUE(lag.record(t, prior, belief).accepted());
    if (k % 4 == 0) {  // a second sensor at the same time, biased: joins the record
      Sensor biased;
      biased.H << 1.0, 0.0, 1.0, 0.0;
      biased.R << 0.04;
      const Gaussian<N> between = belief;
      EXPECT_TRUE(ekf::update<N>(biased, belief, Vector<1>(truth_p + truth_b + 0.2 * rng.normal())).accepted());
      EXPECT_TRUE(lag.record(t, between, belief).accepted());
    }
    out.push_back({t, prior.mean, belief.mean, prior.cov, belief.cov, phi});
  }
  return out;
}

/// The textbook RTS over epochs[0..last]: the smoothed mean of every epoch.
std::vector<Vector<N>> textbook_rts(const std::vector<Epoch>& e, std::size_t last) {
  std::vector<Vector<N>> xs(last + 1);
  xs[last] = e[last].mean;
  for (std::size_t k = last; k-- > 0;) {
    SquareMatrix<N> pbar = e[k + 1].prior_cov;
    pbar(3, 3) = 1.0;  // the held state: zero row and column; its gain is zero either way
    const SquareMatrix<N> C = e[k].cov * e[k + 1].phi.transpose() * pbar.inverse();
    xs[k] = e[k].mean + C * (xs[k + 1] - e[k + 1].prior_mean);
  }
  return xs;
}

TEST(FixedLagRts, EqualsTheTextbookRtsOverTheWholeRun) {
  FixedLagRts<N> lag(128);
  const auto e = run(60, lag, 11);
  const auto xs = textbook_rts(e, e.size() - 1);
  for (double lag_s : {0.0, 0.3, 1.0, 2.5, 100.0}) {
    const auto s = lag.smoothed(lag_s);
    // The newest epoch at least lag_s before the newest one (the first one for 100 s).
    std::size_t k = e.size() - 1;
    while (k > 0 && e[k].t > e.back().t - lag_s) --k;
    EXPECT_DOUBLE_EQ(s.t, e[k].t) << lag_s;
    EXPECT_LT((s.mean - xs[k]).cwiseAbs().maxCoeff(), 1e-9) << lag_s;
    EXPECT_EQ(s.mean(3), 2.0);  // the held state is not moved
  }
  // The smoothing did something: at 1 s back the smoothed position differs from the filtered.
  std::size_t k = e.size() - 1;
  while (e[k].t > e.back().t - 1.0) --k;
  EXPECT_GT(std::abs(lag.smoothed(1.0).mean(0) - e[k].mean(0)), 1e-3);
}

TEST(FixedLagRts, ALongerRunThanTheRingSmoothsWithinTheLagExactly) {
  FixedLagRts<N> lag(16);
  const auto e = run(100, lag, 12);
  const auto xs = textbook_rts(e, e.size() - 1);
  const auto s = lag.smoothed(1.0);  // about 8 records back: inside the ring
  std::size_t k = e.size() - 1;
  while (e[k].t > e.back().t - 1.0) --k;
  EXPECT_DOUBLE_EQ(s.t, e[k].t);
  EXPECT_LT((s.mean - xs[k]).cwiseAbs().maxCoeff(), 1e-9);
  // A lag beyond the ring: the oldest record held, smoothed over what the ring holds.
  EXPECT_EQ(lag.size(), 16);
  const auto oldest = lag.smoothed(1e9);
  EXPECT_DOUBLE_EQ(oldest.t, e[e.size() - 16].t);
  EXPECT_LT((oldest.mean - xs[e.size() - 16]).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(FixedLagRts, RefusedRecordsLeaveTheWindowAsItWas) {
  FixedLagRts<N> lag(32);
  Gaussian<N> g;
  EXPECT_EQ(lag.record(1.0, g, g).outcome, Outcome::invalid_input);  // before start
  const auto e = run(10, lag, 13);
  const auto before = lag.smoothed(0.5);
  const int size = lag.size();
  EXPECT_EQ(lag.record(e.back().t - 0.01, g, g).problem, Problem::out_of_order_time);
  EXPECT_EQ(lag.size(), size);
  EXPECT_EQ(lag.smoothed(0.5).mean, before.mean);
  // A prior that is not positive definite ends the run: a new one starts from the posterior.
  Gaussian<N> bad = g;
  bad.cov(0, 0) = -1.0;
  lag.predicted(SquareMatrix<N>::Identity());
  Gaussian<N> post;
  post.mean.setConstant(7.0);
  EXPECT_EQ(lag.record(e.back().t + 0.1, bad, post).problem, Problem::covariance_not_positive_definite);
  EXPECT_EQ(lag.size(), 1);
  EXPECT_EQ(lag.smoothed(10.0).mean, post.mean);
}

}  // namespace

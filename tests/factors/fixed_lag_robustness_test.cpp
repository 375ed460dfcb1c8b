// Bad input leaves the smoother's window exactly as it was, with the Status naming the
// problem; epochs without ranges and stationary periods keep the system well posed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include <Eigen/LU>

#include "ctxfuse/filters/fixed_lag.hpp"
#include "straight_turn.hpp"

namespace {
using namespace ctxfuse;
using test::Cv2;
using test::Range2;
using test::StraightTurnDrive;
using Smoother = FixedLagSmoother<Cv2, Range2, 6, 4>;

Smoother::Measurements ranges(const StraightTurnDrive& drive, std::size_t k) {
  Smoother::Measurements m;
  for (int a = 0; a < 4; ++a) m.add(drive.range(a), Vector<1>(drive.epochs[k].ranges[static_cast<std::size_t>(a)]));
  return m;
}

Gaussian<4> start(const StraightTurnDrive& drive) {
  Gaussian<4> g;
  g.mean = drive.epochs[0].truth;
  g.cov = SquareMatrix<4>::Identity();
  return g;
}

/// Everything the window holds, compared bit for bit.
void expect_same_window(const Smoother::Window& a, const Smoother::Window& b) {
  ASSERT_EQ(a.size, b.size);
  EXPECT_EQ(std::memcmp(&a.prior, &b.prior, sizeof a.prior), 0);
  EXPECT_EQ(std::memcmp(&a.newest_cov, &b.newest_cov, sizeof a.newest_cov), 0);
  for (int i = 0; i < a.size; ++i) {
    const auto k = static_cast<std::size_t>(i);
    EXPECT_EQ(a.epochs[k].time, b.epochs[k].time);
    EXPECT_EQ(std::memcmp(a.epochs[k].x.data(), b.epochs[k].x.data(), sizeof(double) * 4), 0);
    EXPECT_EQ(a.epochs[k].factor_count, b.epochs[k].factor_count);
  }
}

TEST(FixedLagRobustness, BadInputLeavesTheWindowUnchanged) {
  const StraightTurnDrive drive(7, 3.0);
  Smoother s(drive.motion());
  EXPECT_EQ(s.step(0.1, {}, ranges(drive, 1)).problem, Problem::time_not_set);
  ASSERT_TRUE(s.initialise(0.0, start(drive)));
  for (std::size_t k = 1; k < 10; ++k) ASSERT_TRUE(s.step(drive.epochs[k].t, {}, ranges(drive, k)));
  ASSERT_EQ(s.window().size, 6);  // full: the next step would marginalise
  const Smoother::Window before = s.window();
  const double t = drive.epochs[10].t;

  const auto expect_refused = [&](Status st, Outcome outcome, Problem problem) {
    EXPECT_EQ(st.outcome, outcome) << describe(st.problem);
    EXPECT_EQ(st.problem, problem) << describe(st.problem);
    expect_same_window(s.window(), before);
  };
  expect_refused(s.step(std::nan(""), {}, ranges(drive, 10)), Outcome::invalid_input, Problem::non_finite_dt);
  expect_refused(s.step(drive.epochs[5].t, {}, ranges(drive, 10)), Outcome::invalid_input, Problem::out_of_order_time);
  expect_refused(s.step(s.time(), {}, ranges(drive, 10)), Outcome::invalid_input, Problem::non_positive_dt);
  expect_refused(s.step(s.time() + 100.0, {}, ranges(drive, 10)), Outcome::invalid_input, Problem::dt_above_maximum);

  Smoother::Measurements m = ranges(drive, 10);
  m.z[2](0) = std::numeric_limits<double>::infinity();
  expect_refused(s.step(t, {}, m), Outcome::invalid_input, Problem::non_finite_measurement);
  m = ranges(drive, 10);
  m.z[1](0) = -3.0;
  expect_refused(s.step(t, {}, m), Outcome::invalid_input, Problem::measurement_out_of_domain);
  m = ranges(drive, 10);
  m.z[0](0) = 1e12;
  expect_refused(s.step(t, {}, m), Outcome::invalid_input, Problem::measurement_magnitude);
  m = ranges(drive, 10);
  m.models[3].sigma = std::nan("");
  expect_refused(s.step(t, {}, m), Outcome::invalid_input, Problem::measurement_noise_non_finite);
  m = ranges(drive, 10);
  m.count = 5;
  expect_refused(s.step(t, {}, m), Outcome::invalid_input, Problem::measurement_count_above_capacity);
  Gaussian<4> bad = start(drive);
  bad.mean(1) = std::nan("");
  expect_refused(s.initialise(0.0, bad), Outcome::invalid_input, Problem::non_finite_state);

  // Too few iterations for the tolerance: refused as not converged, nothing committed.
  FixedLagOptions one;
  one.max_iterations = 1;
  Smoother hurried(drive.motion(), one);
  EXPECT_EQ(hurried.initialise(0.0, start(drive), ranges(drive, 0)).problem, Problem::not_converged);
  EXPECT_FALSE(hurried.initialised());

  // A slot left out (the NLOS mask) is not validated: its value never enters the graph.
  m = ranges(drive, 10);
  m.z[2](0) = std::nan("");
  m.attached[2] = false;
  ASSERT_TRUE(s.step(t, {}, m));
  EXPECT_EQ(s.window().epochs[5].factor_count, 3);
  EXPECT_EQ(s.window().epochs[0].time, before.epochs[1].time);
}

TEST(FixedLagRobustness, EpochsWithoutRangesAndStationaryPeriodsStayWellPosed) {
  const StraightTurnDrive drive(8, 3.0);
  Smoother s(drive.motion());
  ASSERT_TRUE(s.initialise(0.0, start(drive)));
  // 60 epochs with every range left out: the motion factors alone, through 54 marginalisations.
  double previous_trace = s.newest_covariance().trace();
  for (int k = 1; k <= 60; ++k) {
    Smoother::Measurements none = ranges(drive, 0);
    none.attached.fill(false);
    ASSERT_TRUE(s.step(0.1 * k, {}, none)) << k;
    const double trace = s.newest_covariance().trace();
    EXPECT_GT(trace, previous_trace) << k;  // uncertainty only grows without measurements
    previous_trace = trace;
  }
  // Dead reckoning at the initial velocity: the prediction, unchanged by the solve.
  EXPECT_LT((s.newest().head<2>() - (drive.epochs[0].truth.head<2>() + 6.0 * drive.epochs[0].truth.tail<2>())).norm(), 1e-9);

  // Then stationary at one point, ranged: the estimate settles there, velocity to zero.
  const Vector<2> parked(3.0, -4.0);
  sim::Rng rng(9, sim::Stream::uwb);
  double largest_nees = 0.0;
  for (int k = 61; k <= 260; ++k) {
    Smoother::Measurements m;
    for (int a = 0; a < 4; ++a)
      m.add(drive.range(a), Vector<1>((parked - drive.anchors[static_cast<std::size_t>(a)]).norm() + 0.1 * rng.normal()));
    ASSERT_TRUE(s.step(0.1 * k, {}, m)) << k;
    if (k < 80) continue;  // 2 s after the jump from the dead-reckoned point
    // The error against the smoother's own covariance (4 dof): a covariance that were too
    // small, or a biased estimate, would exceed the 99.9 % chi-square quantile.
    Vector<4> err = s.newest();
    err.head<2>() -= parked;
    largest_nees = std::max(largest_nees, err.dot(s.newest_covariance().inverse() * err));
  }
  EXPECT_LT(largest_nees, chi_square_quantile(0.999, 4));
  // The covariance is the information's inverse: positive definite and shrunk by the ranges.
  EXPECT_TRUE(is_positive_definite(s.newest_covariance()));
  EXPECT_LT(s.newest_covariance().trace(), previous_trace);
}

}  // namespace

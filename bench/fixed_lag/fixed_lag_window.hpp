// The benchmark window of bench_fixed_lag and bench_per_sample: a fixed-lag smoother (window
// of 10 planar position-velocity states, 4 UWB ranges per epoch, constant-velocity motion) on a
// periodic drive, a snapshot of one step, and Ceres 2.1 solving that same window from the same
// starting point (autodiff costs from the same factors, via tests/factors/ceres_factors.hpp).
#pragma once

#include <benchmark/benchmark.h>
#include <ceres/ceres.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numbers>
#include <utility>
#include <vector>

// From tests/factors: the factors as autodiff costs, and the tests' planar types.
#include "ceres_factors.hpp"
#include "ctxfuse/filters/fixed_lag.hpp"
#include "ctxfuse/sim/random.hpp"
#include "straight_turn.hpp"

namespace ctxfuse::bench::fixed_lag_window {
using namespace ctxfuse;
using Range = test::Range2;
using Cv = test::Cv2;
constexpr int K = 10;
using Smoother = FixedLagSmoother<Cv, Range, K, 4>;
constexpr double dt = 0.1;

/// A circle of radius 20 m at 5 m/s inside 4 anchors, ranged at 10 Hz with sigma 0.1 m; 1000
/// epochs of noise reused periodically (the circle's period is a multiple of the epoch).
struct Drive {
  std::array<Vector<2>, 4> anchors{Vector<2>(-30, -30), Vector<2>(30, -30), Vector<2>(30, 30), Vector<2>(-30, 30)};
  std::vector<std::array<double, 4>> ranges;
  static constexpr int period = 1000;
  Drive() {
    sim::Rng rng(1, sim::Stream::uwb);
    for (int k = 0; k < period; ++k) {
      const double phi = 2.0 * std::numbers::pi * k / period;
      const Vector<2> p = 20.0 * Vector<2>(std::cos(phi), std::sin(phi));
      std::array<double, 4> r{};
      for (std::size_t a = 0; a < 4; ++a) r[a] = (p - anchors[a]).norm() + 0.1 * rng.normal();
      ranges.push_back(r);
    }
  }
  Smoother::Measurements measurements(long k) const {
    Smoother::Measurements m;
    for (std::size_t a = 0; a < 4; ++a) {
      Range r;
      r.anchor = anchors[a];
      r.sigma = 0.1;
      m.add(r, Vector<1>(ranges[static_cast<std::size_t>(k % period)][a]));
    }
    return m;
  }
  Gaussian<4> start() const {
    Gaussian<4> g;
    const double v = 2.0 * std::numbers::pi * 20.0 / (period * dt);
    g.mean << 20.0, 0.0, 0.0, v;
    return g;
  }
  Cv motion() const {
    Cv cv;
    cv.accel_psd = 0.156;  // a^2 dt for the 1.25 m/s^2 turn of the tests' drive
    return cv;
  }
};

inline const Drive& drive() {
  static const Drive d;
  return d;
}

/// A smoother stepping along the drive, one epoch per call, counting refused steps.
struct DriveStream {
  std::unique_ptr<Smoother> smoother = std::make_unique<Smoother>(drive().motion());
  long k = 0;
  int refused = 0;
  DriveStream() { (void)smoother->initialise(0.0, drive().start()); }
  /// Epoch k + 1 with the given measurements (default: the drive's 4 ranges, all attached).
  void step(const Smoother::Measurements& meas) {
    ++k;
    refused += !smoother->step(static_cast<double>(k) * dt, {}, meas).accepted();
  }
  void step() { step(drive().measurements(k + 1)); }
};

/// The snapshot: a smoother after 200 steps (window full, marginalised prior), a copy of it
/// taken before step 201, and the starting point its solve uses (the states before, shifted,
/// and the prediction of the new one).
struct Snapshot {
  std::unique_ptr<Smoother> before = std::make_unique<Smoother>(drive().motion());
  std::unique_ptr<Smoother> after;
  std::array<Vector<4>, K> start{};
  Smoother::Measurements meas;
  double t = 0.0;
  Snapshot() {
    (void)before->initialise(0.0, drive().start());
    for (long k = 1; k <= 200; ++k) (void)before->step(k * dt, {}, drive().measurements(k));
    t = 201 * dt;
    meas = drive().measurements(201);
    after = std::make_unique<Smoother>(*before);
    (void)after->step(t, {}, meas);
    for (int i = 1; i < K; ++i) start[static_cast<std::size_t>(i - 1)] = before->window().epochs[static_cast<std::size_t>(i)].x;
    start[K - 1] = drive().motion().predict(before->newest(), {}, dt, nullptr);
  }
};

inline const Snapshot& snapshot() {
  static const Snapshot s;
  return s;
}

/// Times `step(smoother)` on copies of `before`, the copies made with the timer paused,
/// kCopies at a time, so that only steps are timed: a smoother holds two windows and two
/// normal-equation systems (25 kB and more), and copying one before every step, which no user
/// does, cost a fifth of a step. Each copy's step starts with its data in L2 rather than L1
/// (16 copies, 400 kB and more), as a user's step does after other work. The pause (two clock
/// reads) is paid once per 16 steps. `step` returns false when refused. Returns the smoother
/// stepped last.
template <class S, class Step>
std::unique_ptr<S> step_copies(benchmark::State& state, const S& before, Step step) {
  constexpr int kCopies = 16;
  std::vector<std::unique_ptr<S>> copies;
  for (int i = 0; i < kCopies; ++i) copies.push_back(std::make_unique<S>(before));
  int next = kCopies, last = 0;
  for (auto _ : state) {
    if (next == kCopies) {
      state.PauseTiming();
      for (auto& c : copies) *c = before;
      next = 0;
      state.ResumeTiming();
    }
    S& s = *copies[static_cast<std::size_t>(next)];
    if (!step(s)) state.SkipWithError("the step was refused");
    benchmark::DoNotOptimize(s.newest().data());
    last = next++;
  }
  return std::move(copies[static_cast<std::size_t>(last)]);
}

/// Times step 201 on copies of the snapshot's smoother (step_copies).
inline std::unique_ptr<Smoother> step_snapshot_copies(benchmark::State& state) {
  const Snapshot& snap = snapshot();
  return step_copies(state, *snap.before, [&](Smoother& s) { return s.step(snap.t, {}, snap.meas).accepted(); });
}

/// Largest element of the difference between states xs and a smoother window's solution.
template <class States, class Window>
double gap_to_window(const States& xs, const Window& w) {
  double gap = 0.0;
  for (int i = 0; i < w.size; ++i)
    gap = std::max(gap, (xs[static_cast<std::size_t>(i)] - w.epochs[static_cast<std::size_t>(i)].x).cwiseAbs().maxCoeff());
  return gap;
}

/// Builds the snapshot window as a Ceres problem from the smoother's starting point, solves
/// it and returns the largest difference from the smoother's solution.
inline double solve_with_ceres(const ceres::Solver::Options& options, ceres::Solver::Summary& summary) {
  const Smoother::Window& w = snapshot().after->window();
  std::array<Vector<4>, K> xs = snapshot().start;
  ceres::Problem problem;
  test::add_window(w, xs, problem);
  ceres::Solve(options, &problem, &summary);
  return gap_to_window(xs, w);
}

inline ceres::Solver::Options ceres_options(ceres::LinearSolverType solver) {
  ceres::Solver::Options o;
  o.linear_solver_type = solver;
  o.num_threads = 1;
  o.max_num_iterations = 50;
  o.function_tolerance = 1e-12;
  o.gradient_tolerance = 1e-12;
  o.parameter_tolerance = 1e-10;
  o.logging_type = ceres::SILENT;
  return o;
}

}  // namespace ctxfuse::bench::fixed_lag_window

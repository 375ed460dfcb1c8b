// The core of examples/smoother.cpp: the models of the first filter (first_filter.hpp) in the
// fixed-lag smoother, next to the EKF on the same measurements. The smoother keeps the last K
// states and solves them together at every step, relinearising the range-bearing factors of
// the whole window; the state K-1 epochs back is estimated from the K-1 epochs after it too.
// tests/examples/smoother_example_test.cpp checks the windows against a Gauss-Newton solution
// of the whole run written out by hand. docs/smoother.md walks through this file.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/fixed_lag.hpp"
#include "ctxfuse/sim/random.hpp"
#include "first_filter.hpp"

namespace smoother_example {
using namespace ctxfuse;
using first_filter::ConstantVelocity;
using first_filter::L;
using first_filter::RangeBearing;

constexpr int kLag = 5;  // states in the window
constexpr int kPerEpoch = 1;  // measurements an epoch can carry
using Smoother = FixedLagSmoother<ConstantVelocity, RangeBearing, kLag, kPerEpoch>;

struct Settings {
  std::uint64_t seed = 1;
  int steps = 30;
  double dt = 1.0;  // [s]
  FixedLagOptions options{};
};

struct Step {
  double t = 0.0;
  Vector<4> truth;
  Vector<2> z;
  Status smoothed;                   // the smoother's step
  int iterations = 0;                // Gauss-Newton iterations of that step
  std::array<double, kLag> times{};  // the window after the step, oldest first
  std::array<Vector<4>, kLag> window{};
  int window_size = 0;
  Gaussian<4> newest;  // the smoother's newest state and its marginal covariance
  Gaussian<4> ekf;     // the EKF's posterior on the same measurements
};

struct Run {
  Settings settings;
  ConstantVelocity model;
  RangeBearing sensor;
  Gaussian<4> initial;
  std::vector<Step> steps;
  // Horizontal RMS errors over the epochs that have a lagged estimate (all but the last K-1):
  // the EKF's, the smoother's newest state at that epoch, and the smoother's estimate of that
  // epoch K-1 steps later (the oldest state of its window then).
  double rms_ekf = 0.0, rms_newest = 0.0, rms_lagged = 0.0;
};

/// The window of a smoother of kLag states (any measurement model), oldest first, into `step`.
template <class S>
void record_window(const S& smoother, Step& step) {
  const auto& w = smoother.window();
  step.window_size = w.size;
  for (int i = 0; i < w.size; ++i) {
    step.times[static_cast<std::size_t>(i)] = w.epochs[static_cast<std::size_t>(i)].time;
    step.window[static_cast<std::size_t>(i)] = w.epochs[static_cast<std::size_t>(i)].x;
  }
}

inline Run run(const Settings& s = {}) {
  Run out;
  out.settings = s;
  out.initial.mean << 20.0, 10.0, 0.0, 0.0;  // as the first filter: about there, at rest
  out.initial.cov = Vector<4>(4.0, 4.0, 4.0, 4.0).asDiagonal();

  // The smoother holds two windows and two normal-equation systems by value (8.6 kB here,
  // growing as K (C + dim^2)): on the heap or as a member, not on a small stack.
  auto smoother = std::make_unique<Smoother>(out.model, s.options);
  (void)smoother->initialise(0.0, out.initial);  // a finite prior and time: accepted
  Ekf<ConstantVelocity> ekf(out.model, out.initial);

  out.steps.reserve(static_cast<std::size_t>(s.steps));
  sim::Rng rng(s.seed);
  Vector<4> truth(20.0, 10.0, 1.0, -0.5);
  for (int k = 1; k <= s.steps; ++k) {
    truth = out.model.predict(truth, {}, s.dt, nullptr);
    const double noise_range = rng.normal(), noise_bearing = rng.normal();
    Step step;
    step.t = k * s.dt;
    step.truth = truth;
    step.z = out.sensor.predict(truth, nullptr) +
             Vector<2>(out.sensor.sigma_range * noise_range, out.sensor.sigma_bearing * noise_bearing);

    Smoother::Measurements m;
    m.add(out.sensor, step.z);  // one slot: the sensor's model and its measurement
    step.smoothed = smoother->step(step.t, {}, m);
    step.iterations = smoother->report().iterations;
    record_window(*smoother, step);
    step.newest = smoother->newest_belief();

    (void)ekf.predict({}, s.dt);
    (void)ekf.update(out.sensor, step.z);
    step.ekf = ekf.belief();
    out.steps.push_back(step);
  }

  // Epoch j's lagged estimate is the oldest state of the window K-1 steps later.
  double se_ekf = 0.0, se_newest = 0.0, se_lagged = 0.0;
  int n = 0;
  for (std::size_t j = 0; j + kLag - 1 < out.steps.size(); ++j) {
    const Step& at = out.steps[j];
    const Step& later = out.steps[j + kLag - 1];
    se_ekf += (L::get<"p">(at.ekf.mean) - L::get<"p">(at.truth)).squaredNorm();
    se_newest += (L::get<"p">(at.newest.mean) - L::get<"p">(at.truth)).squaredNorm();
    se_lagged += (L::get<"p">(later.window[0]) - L::get<"p">(at.truth)).squaredNorm();
    ++n;
  }
  out.rms_ekf = std::sqrt(se_ekf / n);
  out.rms_newest = std::sqrt(se_newest / n);
  out.rms_lagged = std::sqrt(se_lagged / n);
  return out;
}

}  // namespace smoother_example

// The core of examples/first_filter.cpp: a state layout, a process model and a measurement
// model of one's own, an EKF with a chi-square gate, and the refusals of bad input.
// tests/examples/examples_test.cpp calls run() too and checks its numbers against an EKF
// written out by hand. docs/first_filter.md walks through this file.
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <vector>

#include "ctxfuse/core/concepts.hpp"
#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/policies/gating.hpp"
#include "ctxfuse/sim/random.hpp"

namespace first_filter {
using namespace ctxfuse;

// The state: position and velocity in the plane, two named blocks of 2.
using L = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;

// Process model: constant velocity driven by white acceleration of density accel_psd.
struct ConstantVelocity {
  static constexpr int dim = L::size;
  using State = Vector<dim>;
  using Input = NoInput;
  double accel_psd = 0.05;  // [m^2/s^3]

  State predict(const State& x, const Input&, double dt, SquareMatrix<dim>* F) const {
    State out = x;
    L::get<"p">(out) += dt * L::get<"v">(x);
    if (F) {  // the Jacobian only when the caller asks for it
      F->setIdentity();
      L::cov<"p", "v">(*F) = dt * SquareMatrix<2>::Identity();
    }
    return out;
  }
  SquareMatrix<dim> noise(const State&, const Input&, double dt) const {
    const SquareMatrix<2> I = SquareMatrix<2>::Identity();
    SquareMatrix<dim> Q;
    L::cov<"p">(Q) = accel_psd * dt * dt * dt / 3.0 * I;
    L::cov<"p", "v">(Q) = accel_psd * dt * dt / 2.0 * I;
    L::cov<"v", "p">(Q) = accel_psd * dt * dt / 2.0 * I;
    L::cov<"v">(Q) = accel_psd * dt * I;
    return Q;
  }
};
static_assert(VectorProcessModel<ConstantVelocity>);

// Measurement model: range [m] and bearing [rad] of the target from a sensor at a known point.
struct RangeBearing {
  static constexpr int dim = 2;
  Vector<2> sensor = Vector<2>::Zero();
  double sigma_range = 0.5;     // [m]
  double sigma_bearing = 0.01;  // [rad]

  Vector<2> predict(const Vector<L::size>& x, Matrix<2, L::size>* H) const {
    const Vector<2> d = L::get<"p">(x) - sensor;
    const double r2 = d.squaredNorm(), r = std::sqrt(r2);
    if (H) {
      H->setZero();
      L::cols<"p">(*H) << d.x() / r, d.y() / r, -d.y() / r2, d.x() / r2;
    }
    return Vector<2>(r, std::atan2(d.y(), d.x()));
  }
  SquareMatrix<2> noise(const Vector<L::size>&) const {
    return Vector<2>(sigma_range * sigma_range, sigma_bearing * sigma_bearing).asDiagonal();
  }
  // Optional: the innovation, with the bearing difference wrapped into [-pi, pi).
  Vector<2> residual(const Vector<2>& z, const Vector<2>& z_pred) const {
    const double two_pi = 2.0 * std::numbers::pi;
    const double db = z(1) - z_pred(1);
    return Vector<2>(z(0) - z_pred(0), db - two_pi * std::floor((db + std::numbers::pi) / two_pi));
  }
  // Optional: a negative range is not a measurement.
  Problem check(const Vector<2>& z) const {
    return z(0) < 0.0 ? Problem::measurement_out_of_domain : Problem::none;
  }
};
static_assert(MeasurementModel<RangeBearing, Vector<L::size>, L::size>);

using Filter = Ekf<ConstantVelocity, policies::ChiSquareGate>;

struct Settings {
  std::uint64_t seed = 1;
  int steps = 12;
  double dt = 1.0;           // [s]
  int outlier_step = 8;      // this step's range is off by outlier_m
  double outlier_m = 12.0;
  double gate_probability = 0.99;
};

struct Step {
  double t = 0.0;
  Vector<4> truth;
  Vector<2> z;
  Status predicted, scored, updated;  // predict(), score() (before the update), update()
  Gaussian<L::size> prior, posterior;  // the belief after the prediction, after the update
};

struct Refusal {
  const char* what;
  Status status;
  Gaussian<L::size> before, after;  // the belief around the refused call
};

struct Run {
  Settings settings;
  ConstantVelocity model;
  RangeBearing sensor;
  Gaussian<L::size> initial;
  std::vector<Step> steps;
  std::vector<Refusal> refusals;
};

inline Run run(const Settings& s = {}) {
  Run out;
  out.settings = s;
  out.initial.mean << 20.0, 10.0, 0.0, 0.0;  // a first guess: about where the target is, at rest
  out.initial.cov = Vector<4>(4.0, 4.0, 4.0, 4.0).asDiagonal();
  Filter filter(out.model, out.initial, FilterOptions{}, policies::ChiSquareGate(s.gate_probability));

  sim::Rng rng(s.seed);
  Vector<4> truth(20.0, 10.0, 1.0, -0.5);
  for (int k = 1; k <= s.steps; ++k) {
    truth = out.model.predict(truth, {}, s.dt, nullptr);  // no Jacobian asked for
    const double noise_range = rng.normal(), noise_bearing = rng.normal();  // in this order
    Step step;
    step.t = k * s.dt;
    step.truth = truth;
    step.z = out.sensor.predict(truth, nullptr) +
             Vector<2>(out.sensor.sigma_range * noise_range, out.sensor.sigma_bearing * noise_bearing);
    if (k == s.outlier_step) step.z(0) += s.outlier_m;

    step.predicted = filter.predict({}, s.dt);
    step.prior = filter.belief();
    step.scored = filter.score(out.sensor, step.z);  // NIS and log-likelihood; changes nothing
    step.updated = filter.update(out.sensor, step.z);
    step.posterior = filter.belief();
    out.steps.push_back(step);
  }

  // Bad input: each call is refused, says why, and leaves the belief as it was.
  auto refuse = [&](const char* what, auto call) {
    const Gaussian<L::size> before = filter.belief();
    const Status status = call();
    out.refusals.push_back({what, status, before, filter.belief()});
  };
  const Vector<2> z = out.steps.back().z;
  const Eigen::VectorXd three = Eigen::VectorXd::Zero(3);  // a size known only at run time
  const double nan = std::numeric_limits<double>::quiet_NaN();
  refuse("z of size 3", [&] { return filter.update(out.sensor, three); });
  refuse("z with a NaN", [&] { return filter.update(out.sensor, Vector<2>(z(0), nan)); });
  refuse("negative range", [&] { return filter.update(out.sensor, Vector<2>(-z(0), z(1))); });
  refuse("dt = 0", [&] { return filter.predict({}, 0.0); });
  return out;
}

}  // namespace first_filter

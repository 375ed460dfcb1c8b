// The NLOS paper's fusion for bench_per_sample: a fixed-lag smoother of 10 planar IMU states
// (models/planar.hpp: p, v, heading, yaw-rate bias, accelerometer biases), 4 UWB ranges per
// epoch and, between consecutive states, the IMU factor of the epoch's 10 IMU samples
// preintegrated once (models/planar_preintegration.hpp) -- the factor graph of the paper,
// as pipelines/nlos_uwb/imu_smoother.hpp builds it. A step is the preintegration of the
// epoch's samples plus the smoother's step.
// Beside it, the same window solved by Ceres (sparse normal Cholesky, autodiff costs from the
// same factors through their value<T>) and by Ceres' TinySolver (dense Levenberg-Marquardt,
// given the factors' analytic Jacobians: its best case), each from the smoother's starting
// point to the smoother's solution.
#pragma once

#include <benchmark/benchmark.h>
#include <ceres/ceres.h>
#include <ceres/tiny_solver.h>

#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <utility>
#include <vector>

#include "ceres_factors.hpp"
#include "fixed_lag_window.hpp"
#include "ctxfuse/filters/fixed_lag.hpp"
#include "ctxfuse/models/planar.hpp"
#include "ctxfuse/models/planar_preintegration.hpp"
#include "ctxfuse/pipelines/nlos_uwb/imu_smoother.hpp"
#include "ctxfuse/sim/random.hpp"

namespace ctxfuse::bench::imu_window {
using namespace ctxfuse;
using L = models::PlanarLayout;
using State = Vector<L::size>;
constexpr int K = 10, kAnchors = 4, kImuPerEpoch = 10;
using Motion = models::PlanarPreintegratedModel;
using Smoother = FixedLagSmoother<Motion, models::PlanarRange, K, kAnchors>;
constexpr double dt = 0.1, imu_dt = dt / kImuPerEpoch;

/// The data sheet of the simulator's consumer MEMS IMU: the pipeline's default
/// (pipelines/nlos_uwb/imu_smoother.hpp ImuFusionSettings).
inline models::PlanarImuModel imu_sheet() { return pipelines::nlos_uwb::ImuFusionSettings{}.model(); }

/// A circle of radius 20 m, one lap in 100 s, inside 4 anchors at 2-3 m height, ranged at 10 Hz
/// (sigma 0.1 m) from a tag at 1 m, with a 100 Hz IMU of constant biases and white noise; 1000
/// epochs of noise reused periodically (the lap is 1000 epochs).
struct Drive {
  std::array<Vector<3>, kAnchors> anchors{Vector<3>(-30, -30, 2), Vector<3>(30, -30, 3), Vector<3>(30, 30, 2), Vector<3>(-30, 30, 3)};
  static constexpr int period = 1000;
  static constexpr double radius = 20.0, tag_height = 1.0, sigma = 0.1;
  static constexpr double omega = 2.0 * std::numbers::pi / (period * dt), speed = radius * omega;
  std::vector<std::array<double, kAnchors>> ranges;
  std::vector<std::array<models::PlanarImu, kImuPerEpoch>> imu;  // the samples of (k - 1, k]
  Drive() {
    sim::Rng rr(1, sim::Stream::uwb), ri(1, sim::Stream::imu);
    const models::PlanarImuModel m = imu_sheet();
    const double bg = 1e-4, ba_x = 0.02, ba_y = -0.01;
    for (int k = 0; k < period; ++k) {
      const double phi = 2.0 * std::numbers::pi * k / period;
      const Vector<3> p(radius * std::cos(phi), radius * std::sin(phi), tag_height);
      std::array<double, kAnchors> r{};
      for (std::size_t a = 0; a < kAnchors; ++a) r[a] = (p - anchors[a]).norm() + sigma * rr.normal();
      ranges.push_back(r);
      std::array<models::PlanarImu, kImuPerEpoch> u{};
      for (auto& s : u) {
        s.yaw_rate = omega + bg + m.gyro_noise_density / std::sqrt(imu_dt) * ri.normal();
        s.accel << ba_x + m.accel_noise_density / std::sqrt(imu_dt) * ri.normal(),
            speed * omega + ba_y + m.accel_noise_density / std::sqrt(imu_dt) * ri.normal();
      }
      imu.push_back(u);
    }
  }
  Smoother::Measurements measurements(long k) const {
    Smoother::Measurements m;
    for (std::size_t a = 0; a < kAnchors; ++a) {
      models::PlanarRange r;
      r.anchor = anchors[a];
      r.tag_height = tag_height;
      r.sigma = sigma;
      m.add(r, Vector<1>(ranges[static_cast<std::size_t>(k % period)][a]));
    }
    return m;
  }
  /// Epoch k's IMU factor input, preintegrated at the biases of x (the newest state).
  bool preintegrate(long k, const State& x, models::PlanarPreintegrated& out) const {
    if (out.reset(imu_sheet(), x(L::offset<"bg">()), L::get<"ba">(x)) != Problem::none) return false;
    for (const auto& s : imu[static_cast<std::size_t>(k % period)])
      if (out.add(s, imu_dt) != Problem::none) return false;
    return true;
  }
  Gaussian<L::size> start() const {
    Gaussian<L::size> g;
    g.mean << radius, 0.0, 0.0, speed, std::numbers::pi / 2, 0.0, 0.0, 0.0;
    g.cov = Vector<L::size>(0.01, 0.01, 0.01, 0.01, 1e-3, 1e-8, 4e-4, 4e-4).asDiagonal();
    return g;
  }
};

inline const Drive& drive() {
  static const Drive d;
  return d;
}

/// One epoch: the preintegration of its samples and the smoother's step.
inline bool step(Smoother& s, long k, const Smoother::Measurements& meas, models::PlanarPreintegrated& pre) {
  return drive().preintegrate(k, s.newest(), pre) && s.step(static_cast<double>(k) * dt, pre, meas).accepted();
}

/// A smoother stepping along the drive, one epoch per call, counting refused steps.
struct DriveStream {
  std::unique_ptr<Smoother> smoother = std::make_unique<Smoother>();
  models::PlanarPreintegrated pre;
  long k = 0;
  int refused = 0;
  DriveStream() { (void)smoother->initialise(0.0, drive().start()); }
  void step(const Smoother::Measurements& meas) {
    ++k;
    refused += !imu_window::step(*smoother, k, meas, pre);
  }
  void step() { step(drive().measurements(k + 1)); }
};

/// The snapshot: a smoother after 200 steps (window full, marginalised prior), a copy before
/// step 201, and the starting point its solve uses (the kept states and the new prediction).
struct Snapshot {
  std::unique_ptr<Smoother> before = std::make_unique<Smoother>();
  std::unique_ptr<Smoother> after;
  std::array<State, K> start{};
  Smoother::Measurements meas;
  long k = 201;
  Snapshot() {
    models::PlanarPreintegrated pre;
    (void)before->initialise(0.0, drive().start());
    for (long i = 1; i < k; ++i) (void)step(*before, i, drive().measurements(i), pre);
    meas = drive().measurements(k);
    after = std::make_unique<Smoother>(*before);
    (void)step(*after, k, meas, pre);
    for (int i = 1; i < K; ++i) start[static_cast<std::size_t>(i - 1)] = before->window().epochs[static_cast<std::size_t>(i)].x;
    start[K - 1] = Motion{}.predict(before->newest(), pre, dt, nullptr);
  }
};

inline const Snapshot& snapshot() {
  static const Snapshot s;
  return s;
}

/// Times step 201 (preintegration and smoother step) on copies of the snapshot's smoother
/// (fixed_lag_window.hpp's step_copies).
inline std::unique_ptr<Smoother> step_snapshot_copies(benchmark::State& state) {
  const Snapshot& snap = snapshot();
  models::PlanarPreintegrated pre;
  return fixed_lag_window::step_copies(state, *snap.before, [&](Smoother& s) { return step(s, snap.k, snap.meas, pre); });
}

/// The snapshot window solved by Ceres from the smoother's starting point; returns the largest
/// difference from the smoother's solution.
inline double solve_with_ceres(const ceres::Solver::Options& options, ceres::Solver::Summary& summary) {
  const Smoother::Window& w = snapshot().after->window();
  std::array<State, K> xs = snapshot().start;
  ceres::Problem problem;
  test::add_window(w, xs, problem);
  ceres::Solve(options, &problem, &summary);
  return fixed_lag_window::gap_to_window(xs, w);
}

/// The snapshot window as TinySolver's function: all states stacked (K x 8 parameters), the
/// residuals of the prior, every motion factor and the 4 ranges of every epoch, with the
/// factors' own analytic Jacobians written into the dense column-major Jacobian.
struct TinyWindow {
  static constexpr int kMeas = K * kAnchors;
  using Scalar = double;
  enum { NUM_RESIDUALS = L::size + (K - 1) * L::size + kMeas, NUM_PARAMETERS = K * L::size };
  const Smoother::Window* w = nullptr;

  bool operator()(const double* params, double* residuals, double* jacobian) const {
    using J = Eigen::Map<Eigen::Matrix<double, NUM_RESIDUALS, NUM_PARAMETERS>>;
    auto x = [&](int i) { return State(Eigen::Map<const State>(params + i * L::size)); };
    Eigen::Map<Vector<NUM_RESIDUALS>> r(residuals);
    if (jacobian) J(jacobian).setZero();
    int row = 0;
    SquareMatrix<L::size> A, B;
    r.segment<L::size>(row) = w->prior.evaluate(x(0), jacobian ? &A : nullptr);
    if (jacobian) J(jacobian).block<L::size, L::size>(row, 0) = A;
    row += L::size;
    for (int i = 1; i < K; ++i, row += L::size) {
      const auto& f = w->epochs[static_cast<std::size_t>(i)].motion;
      r.segment<L::size>(row) = f.evaluate(x(i - 1), x(i), jacobian ? &A : nullptr, jacobian ? &B : nullptr);
      if (jacobian) {
        J(jacobian).block<L::size, L::size>(row, (i - 1) * L::size) = A;
        J(jacobian).block<L::size, L::size>(row, i * L::size) = B;
      }
    }
    for (int i = 0; i < K; ++i) {
      const auto& e = w->epochs[static_cast<std::size_t>(i)];
      for (int j = 0; j < kAnchors; ++j, ++row) {
        Matrix<1, L::size> H;
        r.segment<1>(row) = e.factors[static_cast<std::size_t>(j)].evaluate(x(i), jacobian ? &H : nullptr);
        if (jacobian) J(jacobian).block<1, L::size>(row, i * L::size) = H;
      }
    }
    return true;
  }
};

using TinySolver = ceres::TinySolver<TinyWindow>;

/// The snapshot window solved by TinySolver from the smoother's starting point (`solver`
/// holds its workspace: kept by the caller, as a user would); the largest difference from the
/// smoother's solution, or +inf when a factor slot is unattached (the function is for the
/// all-attached window).
inline double solve_with_tiny(TinySolver& solver) {
  const Smoother::Window& w = snapshot().after->window();
  if (w.size != K) return std::numeric_limits<double>::infinity();
  for (int i = 0; i < K; ++i)
    if (w.epochs[static_cast<std::size_t>(i)].factor_count != kAnchors) return std::numeric_limits<double>::infinity();
  TinyWindow f{&w};
  TinySolver::Parameters x;
  for (int i = 0; i < K; ++i) x.segment<L::size>(i * L::size) = snapshot().start[static_cast<std::size_t>(i)];
  solver.Solve(f, &x);
  std::array<State, K> xs{};
  for (int i = 0; i < K; ++i) xs[static_cast<std::size_t>(i)] = x.segment<L::size>(i * L::size);
  return fixed_lag_window::gap_to_window(xs, w);
}

inline void tiny_options(TinySolver& s) {
  s.options.max_num_iterations = 50;
  s.options.function_tolerance = 1e-12;
  s.options.gradient_tolerance = 1e-12;
  s.options.parameter_tolerance = 1e-10;
}

}  // namespace ctxfuse::bench::imu_window

// models::PlanarPreintegratedModel, the IMU factor's process model on a preintegrated
// interval, against independent references:
// - the re-chained interval (models::PlanarImuIntervalModel: PlanarImuModel's steps one by
//   one) at the linearisation biases: prediction, F and Q equal to 1e-9;
// - the first-order bias correction against re-integration at other biases: its error within
//   PlanarPreintegrated::remainder_bound, the bound tight (>= 90 % of it reached) where the
//   error is all heading, and the correction far better than none;
// - Ceres' automatic Jacobians of the motion factor (through value<T>) equal to the analytic
//   ones to 1e-9;
// - the fixed-lag smoother on a simulated planar drive with its true biases unknown at the
//   start: with preintegrated factors its states equal those with re-chained ones within the
//   tolerance that follows from the remainder bound (see the test), and track the truth as
//   closely.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <vector>

#include "ceres_factors.hpp"
#include "ctxfuse/filters/factors.hpp"
#include "ctxfuse/filters/fixed_lag.hpp"
#include "ctxfuse/models/planar.hpp"
#include "ctxfuse/models/planar_interval.hpp"
#include "ctxfuse/models/planar_preintegration.hpp"
#include "ctxfuse/sim/random.hpp"

namespace {
using namespace ctxfuse;
using models::PlanarImu;
using L = models::PlanarLayout;
using X = Vector<L::size>;
using Interval = models::PlanarImuIntervalModel<64>;
using Pre = models::PlanarPreintegratedModel;

PlanarImu imu(double w, double ax, double ay) {
  PlanarImu u;
  u.yaw_rate = w;
  u.accel << ax, ay;
  return u;
}

models::PlanarImuModel sheet() {
  models::PlanarImuModel m;
  m.accel_noise_density = 2e-3;
  m.gyro_noise_density = 1e-4;
  m.gyro_bias_walk = 1e-5;
  m.accel_bias_walk = 1e-3;
  return m;
}

/// An interval of n samples of uneven spans, turning hard with varying specific force.
Interval::Input interval(int n, std::uint64_t seed) {
  sim::Rng rng(seed, sim::Stream::imu);
  Interval::Input u;
  for (int k = 0; k < n; ++k) {
    // One draw per statement: the order of a call's arguments is unspecified.
    const double w = 0.8 * std::sin(0.3 * k) + 0.1 * rng.normal();
    const double ax = 1.5 + rng.normal();
    const double ay = -0.7 + 0.5 * rng.normal();
    u.add(imu(w, ax, ay), 0.01 * (0.5 + rng.uniform()));
  }
  return u;
}

models::PlanarPreintegrated preintegrate(const Interval::Input& u, double bg0, const Vector<2>& ba0) {
  models::PlanarPreintegrated pre;
  EXPECT_EQ(pre.reset(sheet(), bg0, ba0), Problem::none);
  for (int k = 0; k < u.count; ++k)
    EXPECT_EQ(pre.add(u.samples[static_cast<std::size_t>(k)], u.dt[static_cast<std::size_t>(k)]), Problem::none);
  return pre;
}

X state(double psi, double bg, const Vector<2>& ba) {
  X x;
  x << 3.0, -2.0, 4.0, 1.5, psi, bg, ba(0), ba(1);
  return x;
}

TEST(PlanarPreintegration, EqualsTheRechainedIntervalAtItsBiases) {
  const Interval chain{sheet()};
  const Pre pre_model;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const Interval::Input u = interval(static_cast<int>(5 + 7 * seed), seed);
    const Vector<2> ba(0.05 * static_cast<double>(seed), -0.03);
    const double bg = 0.002 * static_cast<double>(seed);
    // Headings on both sides of +-pi, the interval turning across it.
    const X x = state(std::numbers::pi - 0.1 * static_cast<double>(seed), bg, ba);
    const Pre::Input pre = preintegrate(u, bg, ba);
    ASSERT_EQ(pre.count(), u.count);
    ASSERT_NEAR(pre.duration(), u.duration(), 1e-15);
    ASSERT_EQ(pre_model.check(pre, u.duration()), Problem::none);
    SquareMatrix<8> F_chain, F_pre;
    const X a = chain.predict(x, u, u.duration(), &F_chain);
    const X b = pre_model.predict(x, pre, u.duration(), &F_pre);
    EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-9) << seed;
    EXPECT_LT((F_chain - F_pre).cwiseAbs().maxCoeff(), 1e-9) << seed;
    const SquareMatrix<8> Q_chain = chain.noise(x, u, u.duration());
    const SquareMatrix<8> Q_pre = pre_model.noise(x, pre, u.duration());
    EXPECT_LT((Q_chain - Q_pre).cwiseAbs().maxCoeff(), 1e-9 * Q_chain.cwiseAbs().maxCoeff()) << seed;
    EXPECT_GT(std::abs(F_pre(L::offset<"p">(), L::offset<"bg">())), 1e-5);  // the bias columns are not empty
  }
}

/// Re-integration (the re-chained interval) at biases b against the corrected preintegration
/// made at b0: the position and velocity gaps, as norms.
std::pair<double, double> correction_error(const Interval::Input& u, const Pre::Input& pre, const X& x) {
  const X exact = Interval{sheet()}.predict(x, u, u.duration(), nullptr);
  const X corrected = Pre{}.predict(x, pre, u.duration(), nullptr);
  EXPECT_NEAR(exact(L::offset<"psi">()), corrected(L::offset<"psi">()), 1e-12);  // exact in bg
  return {(L::get<"v">(exact) - L::get<"v">(corrected)).norm(), (L::get<"p">(exact) - L::get<"p">(corrected)).norm()};
}

TEST(PlanarPreintegration, BiasCorrectionIsWithinItsFirstOrderBound) {
  const Interval::Input u = interval(40, 11);  // 0.4 s of turning samples
  const Vector<2> ba0(0.1, -0.05);
  const Pre::Input pre = preintegrate(u, 0.003, ba0);
  for (double dbg : {1e-4, 1e-3, 1e-2, 5e-2, -3e-2}) {
    for (double dba : {0.0, 0.02, 0.3}) {
      const Vector<2> d(dba, -0.5 * dba);
      const X x = state(0.7, 0.003 + dbg, ba0 + d);
      const auto [ev, ep] = correction_error(u, pre, x);
      const auto [bv, bp] = pre.remainder_bound(dbg, d);
      EXPECT_LE(ev, bv * (1 + 1e-9) + 1e-13) << dbg << " " << dba;
      EXPECT_LE(ep, bp * (1 + 1e-9) + 1e-13) << dbg << " " << dba;
      // Without the correction the error is first order: the correction removes nearly all.
      const Pre::Input uncorrected = preintegrate(u, 0.003 + dbg, ba0 + d);
      const X exact = Interval{sheet()}.predict(x, u, u.duration(), nullptr);
      X stale = x;  // deltas of b0 used as they are at b
      L::get<"p">(stale) += u.duration() * L::get<"v">(x) + Eigen::Rotation2Dd(0.7).toRotationMatrix() * pre.dp();
      EXPECT_LT((L::get<"p">(Pre{}.predict(x, uncorrected, u.duration(), nullptr)) - L::get<"p">(exact)).norm(), 1e-12);
      EXPECT_LT(ep, 0.05 * (L::get<"p">(stale) - L::get<"p">(exact)).norm()) << dbg << " " << dba;
    }
  }
}

TEST(PlanarPreintegration, BoundIsTightWhereTheErrorIsAllHeading) {
  // Straight (gyro = bias), constant specific force: the deltas' headings are all zero, and
  // with dba = 0 the error is |R(-dbg t) - I + J dbg t| |f| per sample, which tends to the
  // bound's (dbg t)^2 / 2 |f| as dbg t -> 0.
  Interval::Input u;
  for (int k = 0; k < 50; ++k) u.add(imu(0.004, 2.0, 0.0), 0.01);
  const Pre::Input pre = preintegrate(u, 0.004, Vector<2>::Zero());
  const double dbg = 0.02;
  const auto [ev, ep] = correction_error(u, pre, state(-2.0, 0.004 + dbg, Vector<2>::Zero()));
  const auto [bv, bp] = pre.remainder_bound(dbg, Vector<2>::Zero());
  EXPECT_LE(ev, bv);
  EXPECT_LE(ep, bp);
  EXPECT_GT(ev, 0.9 * bv);
  EXPECT_GT(ep, 0.9 * bp);
}

TEST(PlanarPreintegration, CeresJacobiansOfTheMotionFactorEqualTheAnalyticOnes) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const Interval::Input u = interval(12, seed + 20);
    const Vector<2> ba0(0.02, 0.04);
    const Pre::Input pre = preintegrate(u, 0.001, ba0);
    // Linearised away from the preintegration biases, so the correction's columns count.
    const X x0 = state(1.0 + static_cast<double>(seed), 0.001 + 0.01, ba0 + Vector<2>(-0.1, 0.05));
    MotionFactor<Pre> f;
    ASSERT_TRUE(make_motion_factor(Pre{}, pre, u.duration(), x0, f));
    X x1 = Pre{}.predict(x0, pre, u.duration(), nullptr);
    x1 += X::Constant(0.01);
    const test::JacobianGaps g = test::jacobian_gaps(f, x0, x1);
    EXPECT_LT(g.residual, 1e-9) << seed;
    EXPECT_LT(g.slot0, 1e-9) << seed;
    EXPECT_LT(g.slot1, 1e-9) << seed;
  }
}

TEST(PlanarPreintegration, RefusesBadSamplesAndKeepsTheInterval) {
  models::PlanarPreintegrated pre;
  ASSERT_EQ(pre.reset(sheet(), 0.0, Vector<2>::Zero()), Problem::none);
  ASSERT_EQ(pre.add(imu(0.1, 1.0, 0.0), 0.01), Problem::none);
  const Vector<2> dp = pre.dp();
  EXPECT_EQ(pre.add(imu(std::nan(""), 1.0, 0.0), 0.01), Problem::non_finite_input);
  EXPECT_EQ(pre.add(imu(0.1, 1.0, 0.0), 0.0), Problem::non_positive_dt);
  EXPECT_EQ(pre.add(imu(0.1, 1.0, 0.0), -0.01), Problem::non_positive_dt);
  EXPECT_EQ(pre.add(imu(0.1, 1.0, 0.0), std::numeric_limits<double>::infinity()), Problem::non_finite_dt);
  EXPECT_EQ(pre.add(imu(50.0, 1.0, 0.0), 0.01), Problem::input_magnitude);
  EXPECT_EQ(pre.reset(sheet(), std::nan(""), Vector<2>::Zero()), Problem::non_finite_input);
  EXPECT_EQ(pre.count(), 1);
  EXPECT_EQ(pre.dp(), dp);
  EXPECT_EQ(Pre{}.check(pre, 0.02), Problem::dt_above_maximum);  // does not cover the step
  EXPECT_EQ(Pre{}.check(models::PlanarPreintegrated{}, 0.0), Problem::non_finite_input);  // empty
}

// ---- The smoother with either factor on a simulated drive ----

struct Drive {
  struct Epoch {
    double t = 0.0;
    X truth = X::Zero();
    Interval::Input imu{};  // the samples since the previous epoch
    std::array<double, 4> ranges{};
  };
  std::array<Vector<3>, 4> anchors{Vector<3>(-40, -40, 3), Vector<3>(40, -40, 2), Vector<3>(40, 40, 3), Vector<3>(-40, 40, 2)};
  std::vector<Epoch> epochs;
  static constexpr double bg = 0.004;  // the IMU's true biases, unknown to the smoothers
  static constexpr double ba_x = 0.15, ba_y = -0.1;
  static constexpr double sigma = 0.1;

  /// 100 Hz IMU, 10 Hz ranges, speed 6 m/s with weaving turns, for `duration` s.
  explicit Drive(double duration) {
    sim::Rng rng(7, sim::Stream::imu), rr(7, sim::Stream::uwb);
    const models::PlanarImuModel m = sheet();
    const double h = 0.01;
    X x = X::Zero();
    x << -20, -10, 6, 0, 0, bg, ba_x, ba_y;
    Epoch e;
    e.truth = x;
    for (int k = 0; k * h < duration; ++k) {
      const double t = k * h;
      // Turning rate and forward acceleration; the lateral specific force is the centripetal.
      const double w = 0.35 * std::sin(0.4 * t);
      const double fwd = 0.5 * std::cos(0.3 * t);
      const double speed = L::get<"v">(x).norm();
      PlanarImu truth_in = imu(w + bg, fwd + ba_x, speed * w + ba_y);
      x = m.predict(x, truth_in, h, nullptr);  // the motion the smoothers model, exactly
      PlanarImu measured = truth_in;  // one draw per statement (argument order is unspecified)
      measured.yaw_rate += m.gyro_noise_density / std::sqrt(h) * rng.normal();
      measured.accel(0) += m.accel_noise_density / std::sqrt(h) * rng.normal();
      measured.accel(1) += m.accel_noise_density / std::sqrt(h) * rng.normal();
      e.imu.add(measured, h);
      if ((k + 1) % 10 == 0) {
        e.t = (k + 1) * h;
        e.truth = x;
        for (int a = 0; a < 4; ++a) {
          const Vector<2> d = L::get<"p">(x) - anchors[static_cast<std::size_t>(a)].head<2>();
          const double dz = 1.0 - anchors[static_cast<std::size_t>(a)](2);
          e.ranges[static_cast<std::size_t>(a)] = std::sqrt(d.squaredNorm() + dz * dz) + sigma * rr.normal();
        }
        epochs.push_back(e);
        e.imu.clear();
      }
    }
  }
};

template <class Motion, class Make>
std::vector<X> smooth(const Drive& d, const Motion& motion, Make make_input, double* max_bound = nullptr) {
  using S = FixedLagSmoother<Motion, models::PlanarRange, 10, 4>;
  auto s = std::make_unique<S>(motion);
  Gaussian<8> prior;
  prior.mean = d.epochs.front().truth;
  prior.mean(L::offset<"bg">()) = 0.0;  // biases unknown
  prior.mean.tail<2>().setZero();
  prior.cov = Vector<8>(0.01, 0.01, 0.01, 0.01, 1e-4, 1e-4, 0.04, 0.04).asDiagonal();
  EXPECT_TRUE(s->initialise(0.0, prior).accepted());
  std::vector<X> out;
  for (std::size_t k = 1; k < d.epochs.size(); ++k) {
    const auto& e = d.epochs[k];
    typename S::Measurements meas;
    for (int a = 0; a < 4; ++a) {
      models::PlanarRange r;
      r.anchor = d.anchors[static_cast<std::size_t>(a)];
      r.sigma = Drive::sigma;
      meas.add(r, Vector<1>(e.ranges[static_cast<std::size_t>(a)]));
    }
    const X& x_prev = s->newest();
    const auto u = make_input(e.imu, x_prev);
    EXPECT_TRUE(s->step(e.t, u, meas).accepted()) << k;
    out.push_back(s->newest());
    if (max_bound) {
      // The remainder bound of every preintegrated factor in the window at the solution.
      const auto& w = s->window();
      for (int i = 1; i < w.size; ++i) {
        if constexpr (std::is_same_v<Motion, Pre>) {
          const auto& f = w.epochs[static_cast<std::size_t>(i - 1)].x;
          const auto& pre = w.epochs[static_cast<std::size_t>(i)].motion.input;
          const auto [bv, bp] = pre.remainder_bound(f(L::offset<"bg">()) - pre.bg0(), L::get<"ba">(f) - pre.ba0());
          *max_bound = std::max(*max_bound, std::max(bv, bp));
        }
      }
    }
  }
  return out;
}

TEST(PlanarPreintegration, SmootherEqualsTheRechainedOneWithinTheBoundsTolerance) {
  const Drive d(60.0);
  const auto chained = smooth(d, Interval{sheet()}, [](const Interval::Input& u, const X&) { return u; });
  double max_bound = 0.0;
  const auto pre = smooth(
      d, Pre{},
      [](const Interval::Input& u, const X& x) {
        return preintegrate(u, x(L::offset<"bg">()), L::get<"ba">(x));
      },
      &max_bound);
  ASSERT_EQ(chained.size(), pre.size());
  double gap_p = 0.0, gap_bg = 0.0, err_chain = 0.0, err_pre = 0.0;
  for (std::size_t k = 0; k < pre.size(); ++k) {
    gap_p = std::max(gap_p, (L::get<"p">(pre[k]) - L::get<"p">(chained[k])).norm());
    gap_bg = std::max(gap_bg, std::abs(pre[k](L::offset<"bg">()) - chained[k](L::offset<"bg">())));
    err_chain += (L::get<"p">(chained[k]) - L::get<"p">(d.epochs[k + 1].truth)).squaredNorm();
    err_pre += (L::get<"p">(pre[k]) - L::get<"p">(d.epochs[k + 1].truth)).squaredNorm();
  }
  const double n = static_cast<double>(pre.size());
  std::printf("max bound %.3g m, max position gap %.3g m, bg gap %.3g rad/s, RMS %.6f / %.6f m\n", max_bound, gap_p, gap_bg,
              std::sqrt(err_chain / n), std::sqrt(err_pre / n));
  // The smoothers learn the biases (started at zero), so the factors' biases move after their
  // preintegration, and the bound is not vacuous here.
  EXPECT_GT(max_bound, 0.0);
  EXPECT_NEAR(pre.back()(L::offset<"bg">()), Drive::bg, 1e-3);
  // Tolerance from the bound B (largest over the run's factors at their solutions): each
  // factor's prediction differs from the re-chained one by at most B in position and in
  // velocity. Along the window's chain of motion factors (far tighter than the 0.1 m ranges)
  // a position shift carries to the newest state as it is and a velocity shift grows by the
  // time left, at most K dt = 1 s: at most K (1 + K dt / 1 s) B = 20 B from one window's
  // factors; the marginalised prior carries the earlier windows' shifts, damped by their
  // ranges, which we allow as much again: 40 B, plus the solver's convergence floor (steps
  // below 1e-6 with quadratic convergence: 1e-9). An estimate, not a proof; measured: about
  // 6 B (7.6e-6 m against B = 1.3e-6 m).
  EXPECT_LT(gap_p, 40.0 * max_bound + 1e-9);
  // The accuracy on this drive within 1 cm of the re-chained smoother's.
  EXPECT_NEAR(std::sqrt(err_pre / n), std::sqrt(err_chain / n), 0.01);
}

}  // namespace

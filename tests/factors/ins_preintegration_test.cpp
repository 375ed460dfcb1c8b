// models::InsPreintegratedModel, the 3-D IMU factor's process model on a preintegrated
// interval, against independent references:
// - Ins15Model's steps re-chained one by one at the preintegration biases: the predicted state
//   to 1e-9, the Jacobian (the chain's error transition carried to the vector state's
//   coordinates) to 1e-9 and the covariance (the chain's F Q F' + Q_k) to 1e-9 relative;
// - the first-order bias correction against re-integration at other biases: exact in the
//   accelerometer bias alone, second order in the gyro bias (halving the offset quarters the
//   error), and far better than none;
// - Ceres' automatic Jacobians of the motion factor (through value<T> and the templated
//   difference) equal to the analytic ones to 1e-9;
// - bad samples refused with the interval kept;
// - a GNSS/INS fixed-lag window: the smoother with preintegrated factors and position fixes
//   on a simulated 3-D drive, its errors inside its own 3-sigma bounds.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <vector>

#include "ceres_factors.hpp"
#include "ctxfuse/core/so3.hpp"
#include "ctxfuse/filters/factors.hpp"
#include "ctxfuse/filters/fixed_lag.hpp"
#include "ctxfuse/models/ins.hpp"
#include "ctxfuse/models/ins_preintegration.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/sim/random.hpp"

namespace ins_preintegration {
using namespace ctxfuse;
using L = models::Ins15Layout;
using X = Vector<L::size>;
using Pre = models::InsPreintegratedModel;
using models::ImuSample;

struct Sample {
  ImuSample u;
  double dt = 0.0;
};
using Samples = std::vector<Sample>;

/// A consumer-grade IMU's data sheet; biases as random walks (tau infinite), so that the
/// re-chained steps hold them as the preintegration does.
models::Ins15Model sheet() {
  models::Ins15Model m;
  m.gravity = Eigen::Vector3d(0.0, 0.0, -9.80665);
  m.gyro_noise_density = 2e-4;
  m.accel_noise_density = 2e-3;
  m.gyro_bias.density = 1e-5;
  m.accel_bias.density = 1e-4;
  return m;
}

ImuSample imu(const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel) {
  ImuSample u;
  u.gyro = gyro;
  u.accel = accel;
  return u;
}

/// n samples of uneven spans, turning hard about every axis with varying specific force.
Samples interval(int n, std::uint64_t seed) {
  sim::Rng rng(seed, sim::Stream::imu);
  Samples s;
  for (int k = 0; k < n; ++k) {
    Eigen::Vector3d w, f;
    // One draw per statement: the order of a call's arguments is unspecified.
    for (int i = 0; i < 3; ++i) w(i) = 0.6 * std::sin(0.3 * k + i) + 0.2 * rng.normal();
    for (int i = 0; i < 3; ++i) f(i) = (i == 2 ? 9.8 : 1.0) + rng.normal();
    const double dt = 0.01 * (0.5 + rng.uniform());
    s.push_back({imu(w, f), dt});
  }
  return s;
}

double duration(const Samples& s) {
  double t = 0.0;
  for (const auto& e : s) t += e.dt;
  return t;
}

Pre::Input preintegrate(const Samples& s, const Eigen::Vector3d& bg0, const Eigen::Vector3d& ba0) {
  Pre::Input pre;
  EXPECT_EQ(pre.reset(sheet(), bg0, ba0), Problem::none);
  for (const auto& e : s) EXPECT_EQ(pre.add(e.u, e.dt), Problem::none);
  return pre;
}

X state(const Eigen::Vector3d& phi, const Eigen::Vector3d& bg, const Eigen::Vector3d& ba) {
  X x;
  x << 3.0, -2.0, 40.0, 12.0, -4.0, 0.5, phi, bg, ba;
  return x;
}

models::InsState to_ins(const X& x) {
  models::InsState s;
  s.p = L::get<"p">(x);
  s.v = L::get<"v">(x);
  s.q = so3::exp_quat(Eigen::Vector3d(L::get<"theta">(x)));
  s.bg = L::get<"bg">(x);
  s.ba = L::get<"ba">(x);
  return s;
}

/// Ins15Model's steps from x, one by one: the end state, the error transition Phi = F_n..F_1
/// and the chained covariance from zero, all in Ins15Model's error coordinates.
struct Chain {
  models::InsState end;
  SquareMatrix<15> Phi = SquareMatrix<15>::Identity();
  SquareMatrix<15> Q = SquareMatrix<15>::Zero();
};
Chain rechain(const Samples& s, const X& x) {
  const models::Ins15Model m = sheet();
  Chain c;
  c.end = to_ins(x);
  for (const auto& e : s) {
    SquareMatrix<15> F;
    const models::InsState next = m.predict(c.end, e.u, e.dt, &F);
    c.Phi = F * c.Phi;
    c.Q = F * c.Q * F.transpose() + m.noise(c.end, e.u, e.dt);
    c.end = next;
  }
  return c;
}

/// D(phi) = diag(I, I, Jr(phi), I, I): an error-state perturbation of the vector state.
SquareMatrix<15> error_from_vector(const X& x) {
  SquareMatrix<15> D = SquareMatrix<15>::Identity();
  L::cov<"theta">(D) = so3::right_jacobian(Eigen::Vector3d(L::get<"theta">(x)));
  return D;
}

double attitude_gap(const Eigen::Quaterniond& a, const X& x) {
  return so3::log(Eigen::Quaterniond(a.conjugate() * so3::exp_quat(Eigen::Vector3d(L::get<"theta">(x))))).norm();
}

TEST(InsPreintegration, EqualsTheRechainedStepsAtItsBiases) {
  const Pre model;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const Samples s = interval(static_cast<int>(5 + 9 * seed), seed);
    const Eigen::Vector3d bg(0.002 * static_cast<double>(seed), -0.001, 0.003);
    const Eigen::Vector3d ba(0.05 * static_cast<double>(seed), -0.03, 0.1);
    // Attitudes from 0.5 to 3 rad.
    const Eigen::Vector3d phi = Eigen::Vector3d(0.3, -0.5, 0.8).normalized() * (0.5 * static_cast<double>(seed));
    const X x = state(phi, bg, ba);
    const Pre::Input pre = preintegrate(s, bg, ba);
    ASSERT_EQ(pre.count(), static_cast<int>(s.size()));
    ASSERT_EQ(model.check(pre, duration(s)), Problem::none);
    SquareMatrix<15> F;
    const X b = model.predict(x, pre, duration(s), &F);
    const Chain c = rechain(s, x);
    EXPECT_LT((L::get<"p">(b) - c.end.p).norm(), 1e-9) << seed;
    EXPECT_LT((L::get<"v">(b) - c.end.v).norm(), 1e-9) << seed;
    EXPECT_LT(attitude_gap(c.end.q, b), 1e-12) << seed;
    EXPECT_LT((L::get<"bg">(b) - c.end.bg).norm(), 1e-15) << seed;
    EXPECT_LT((L::get<"ba">(b) - c.end.ba).norm(), 1e-15) << seed;
    // The chain's transition in the vector state's coordinates: D(x_j)^-1 Phi D(x_i).
    const SquareMatrix<15> F_chain = error_from_vector(b).inverse() * c.Phi * error_from_vector(x);
    EXPECT_LT((F - F_chain).cwiseAbs().maxCoeff(), 1e-9) << seed;
    EXPECT_GT(std::abs(F(L::offset<"p">(), L::offset<"bg">())), 1e-6) << seed;  // bias columns not empty
    const SquareMatrix<15> Q = model.noise(x, pre, duration(s));
    EXPECT_LT((Q - c.Q).cwiseAbs().maxCoeff(), 1e-9 * c.Q.cwiseAbs().maxCoeff()) << seed;
  }
}

/// Re-integration at the state's biases against the correction of `pre` (made at other
/// biases): the gaps of position, velocity and attitude.
Eigen::Vector3d correction_gap(const Samples& s, const Pre::Input& pre, const X& x) {
  const Chain c = rechain(s, x);
  const X b = Pre{}.predict(x, pre, duration(s), nullptr);
  return {(L::get<"p">(b) - c.end.p).norm(), (L::get<"v">(b) - c.end.v).norm(), attitude_gap(c.end.q, b)};
}

TEST(InsPreintegration, BiasCorrectionIsExactInTheAccelerometerBiasAndSecondOrderInTheGyros) {
  const Samples s = interval(100, 11);  // about 1 s of turning samples
  const Eigen::Vector3d bg0(0.003, -0.002, 0.001), ba0(0.1, -0.05, 0.2);
  const Pre::Input pre = preintegrate(s, bg0, ba0);
  const Eigen::Vector3d phi(0.4, -0.2, 1.1);
  // The accelerometer bias alone: dv and dp are linear in it.
  for (double dba : {0.01, 0.3, -1.0}) {
    const Eigen::Vector3d gap = correction_gap(s, pre, state(phi, bg0, ba0 + Eigen::Vector3d(dba, -0.5 * dba, 0.2 * dba)));
    EXPECT_LT(gap.maxCoeff(), 1e-9) << dba;
  }
  // The gyro bias (with an accelerometer offset too): halving the offsets quarters the gap.
  const Eigen::Vector3d dg(0.02, -0.03, 0.01), da(0.05, 0.02, -0.04);
  Eigen::Vector3d previous = Eigen::Vector3d::Zero();
  for (double scale : {1.0, 0.5, 0.25, 0.125}) {
    const X x = state(phi, bg0 + scale * dg, ba0 + scale * da);
    const Eigen::Vector3d gap = correction_gap(s, pre, x);
    // Without the correction (the deltas of b0 used as they are) the gap is first order.
    const Pre::Input same = preintegrate(s, bg0 + scale * dg, ba0 + scale * da);
    X stale = x;  // the state with the preintegration's biases: the model then uses pre's deltas as they are
    L::get<"bg">(stale) = bg0;
    L::get<"ba">(stale) = ba0;
    const X uncorrected = Pre{}.predict(stale, pre, duration(s), nullptr);
    const X exact = Pre{}.predict(x, same, duration(s), nullptr);  // preintegrated at x's own biases
    const double p_uncorrected = (L::get<"p">(uncorrected) - L::get<"p">(exact)).norm();
    std::printf("scale %.3f: gaps p %.3g m, v %.3g m/s, attitude %.3g rad; uncorrected p gap %.3g m\n", scale, gap(0),
                gap(1), gap(2), p_uncorrected);
    EXPECT_LT(gap(0), 0.01 * p_uncorrected) << scale;
    if (scale < 1.0) {
      for (int i = 0; i < 3; ++i) {
        EXPECT_GT(gap(i), 0.2 * previous(i)) << scale << " " << i;
        EXPECT_LT(gap(i), 0.3 * previous(i)) << scale << " " << i;
      }
    }
    previous = gap;
  }
}

TEST(InsPreintegration, CeresJacobiansOfTheMotionFactorEqualTheAnalyticOnes) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const Samples s = interval(15, seed + 20);
    const Eigen::Vector3d bg0(0.001, 0.002, -0.001), ba0(0.02, 0.04, -0.03);
    const Pre::Input pre = preintegrate(s, bg0, ba0);
    // Linearised away from the preintegration biases, so the correction's columns count.
    const X x0 = state(Eigen::Vector3d(0.2, 0.7 * static_cast<double>(seed), -0.4), bg0 + Eigen::Vector3d(0.01, -0.02, 0.005),
                       ba0 + Eigen::Vector3d(-0.1, 0.05, 0.02));
    MotionFactor<Pre> f;
    ASSERT_TRUE(make_motion_factor(Pre{}, pre, duration(s), x0, f));
    X x1 = Pre{}.predict(x0, pre, duration(s), nullptr);
    x1 += X::Constant(0.01);
    const test::JacobianGaps g = test::jacobian_gaps(f, x0, x1);
    EXPECT_LT(g.residual, 1e-9) << seed;
    EXPECT_LT(g.slot0, 1e-9) << seed;
    EXPECT_LT(g.slot1, 1e-9) << seed;
  }
}

TEST(InsPreintegration, RefusesBadSamplesAndKeepsTheInterval) {
  Pre::Input pre;
  const Eigen::Vector3d w(0.1, 0.0, 0.2), f(0.0, 0.0, 9.8);
  ASSERT_EQ(pre.reset(sheet(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()), Problem::none);
  ASSERT_EQ(pre.add(imu(w, f), 0.01), Problem::none);
  const Eigen::Vector3d dp = pre.dp();
  const SquareMatrix<15> Q = pre.covariance_in_first_frame();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(pre.add(imu(Eigen::Vector3d(nan, 0, 0), f), 0.01), Problem::non_finite_input);
  EXPECT_EQ(pre.add(imu(w, f), 0.0), Problem::non_positive_dt);
  EXPECT_EQ(pre.add(imu(w, f), -0.01), Problem::non_positive_dt);
  EXPECT_EQ(pre.add(imu(w, f), std::numeric_limits<double>::infinity()), Problem::non_finite_dt);
  EXPECT_EQ(pre.add(imu(Eigen::Vector3d(50.0, 0, 0), f), 0.01), Problem::input_magnitude);
  ImuSample increments = imu(w, f);
  increments.increments = true;
  EXPECT_EQ(pre.add(increments, 0.01), Problem::input_wrong_kind);
  EXPECT_EQ(pre.reset(sheet(), Eigen::Vector3d(nan, 0, 0), Eigen::Vector3d::Zero()), Problem::non_finite_input);
  EXPECT_EQ(pre.count(), 1);
  EXPECT_EQ(pre.dp(), dp);
  EXPECT_EQ(pre.covariance_in_first_frame(), Q);
  EXPECT_EQ(Pre{}.check(pre, 0.02), Problem::dt_above_maximum);  // does not cover the step
  EXPECT_EQ(Pre{}.check(Pre::Input{}, 0.0), Problem::non_finite_input);  // empty
}

// ---- A GNSS/INS fixed-lag window on a simulated 3-D drive ----

struct Drive {
  struct Epoch {
    double t = 0.0;
    X truth = X::Zero();
    Samples imu;  // the samples since the previous epoch
    Eigen::Vector3d fix = Eigen::Vector3d::Zero();
  };
  std::vector<Epoch> epochs;
  static constexpr double sigma = 0.5;  // GNSS position [m], each axis
  Eigen::Vector3d bg{0.002, -0.003, 0.001}, ba{0.05, -0.04, 0.08};  // unknown to the smoother

  /// 100 Hz IMU, 10 Hz position fixes; accelerations and body rates that turn the vehicle
  /// about every axis, for `seconds` s. The truth follows Ins15Model's steps exactly, so the
  /// smoother models its motion as it is.
  explicit Drive(double seconds) {
    sim::Rng rng(5, sim::Stream::imu), rg(5, sim::Stream::gnss);
    const models::Ins15Model m = sheet();
    const double h = 0.01;
    models::InsState x;
    x.v = Eigen::Vector3d(8.0, 0.0, 0.0);
    x.bg = bg;
    x.ba = ba;
    Epoch e;
    for (int k = 0; k * h < seconds; ++k) {
      const double t = k * h;
      const Eigen::Vector3d acc(0.6 * std::cos(0.3 * t), 0.8 * std::sin(0.2 * t), 0.1 * std::sin(0.5 * t));
      const Eigen::Vector3d w(0.05 * std::sin(0.7 * t), 0.04 * std::cos(0.4 * t), 0.25 * std::sin(0.25 * t));
      // The specific force that gives `acc` at the current attitude, plus the true biases.
      const ImuSample truth_in = imu(w + bg, x.q.toRotationMatrix().transpose() * (acc - m.gravity) + ba);
      x = m.predict(x, truth_in, h, nullptr);
      ImuSample measured = truth_in;  // one draw per statement (argument order is unspecified)
      for (int i = 0; i < 3; ++i) measured.gyro(i) += m.gyro_noise_density / std::sqrt(h) * rng.normal();
      for (int i = 0; i < 3; ++i) measured.accel(i) += m.accel_noise_density / std::sqrt(h) * rng.normal();
      e.imu.push_back({measured, h});
      if ((k + 1) % 10 == 0) {
        e.t = (k + 1) * h;
        L::get<"p">(e.truth) = x.p;
        L::get<"v">(e.truth) = x.v;
        L::get<"theta">(e.truth) = so3::log(x.q);
        L::get<"bg">(e.truth) = x.bg;
        L::get<"ba">(e.truth) = x.ba;
        for (int i = 0; i < 3; ++i) e.fix(i) = x.p(i) + sigma * rg.normal();
        epochs.push_back(e);
        e.imu.clear();
      }
    }
  }
};

TEST(InsPreintegration, GnssInsFixedLagWindowTracksASimulatedDriveWithinItsOwnBounds) {
  const Drive d(120.0);
  using Fix = models::BlockObservation<L, "p">;
  using S = FixedLagSmoother<Pre, Fix, 10, 1>;
  auto s = std::make_unique<S>(Pre{});
  Gaussian<15> prior;
  prior.mean.setZero();
  L::get<"v">(prior.mean) = Eigen::Vector3d(8.0, 0.0, 0.0);  // biases unknown: zero
  prior.cov = SquareMatrix<15>::Zero();
  prior.cov.diagonal() << Vector<3>::Constant(0.25), Vector<3>::Constant(0.04), Vector<3>::Constant(1e-4),
      Vector<3>::Constant(1e-5), Vector<3>::Constant(0.01);
  ASSERT_TRUE(s->initialise(0.0, prior).accepted());
  Fix fix;
  fix.R = SquareMatrix<3>::Identity() * Drive::sigma * Drive::sigma;
  int outside = 0, count = 0;
  double sum_p = 0.0;
  for (const auto& e : d.epochs) {
    S::Measurements meas;
    meas.add(fix, Vector<3>(e.fix));
    const X& x_prev = s->newest();
    const Pre::Input pre = preintegrate(e.imu, L::get<"bg">(x_prev), L::get<"ba">(x_prev));
    ASSERT_TRUE(s->step(e.t, pre, meas).accepted()) << e.t;
    const X& x = s->newest();
    const SquareMatrix<15> P = s->newest_covariance();
    // Every block's error against its own 3-sigma bound (the attitude as the right-perturbation error).
    const Vector<15> err = Pre{}.difference(x, e.truth);
    for (int i = 0; i < 15; ++i) outside += std::abs(err(i)) > 3.0 * std::sqrt(P(i, i)) ? 1 : 0;
    count += 15;
    sum_p += L::get<"p">(err).squaredNorm();
  }
  const double rms_p = std::sqrt(sum_p / static_cast<double>(d.epochs.size()));
  const X& last = s->newest();
  std::printf("position RMS %.3f m (fixes %.2f m per axis); outside 3 sigma %d of %d; gyro bias error %.2e rad/s\n", rms_p,
              Drive::sigma, outside, count, (L::get<"bg">(last) - d.bg).norm());
  // A consistent estimator leaves 0.27 % of Gaussian errors outside 3 sigma; errors correlated in
  // time make the count noisy, so allow four times that.
  EXPECT_LT(outside, static_cast<int>(0.011 * count));
  // Smoothing ten fixes with the IMU's motion: the error well below one fix's (0.87 m in 3-D).
  EXPECT_LT(rms_p, 0.5);
  // The gyro bias is learnt: within its own 3-sigma bound and far closer than its start (zero).
  EXPECT_LT((L::get<"bg">(last) - d.bg).norm(), 0.3 * d.bg.norm());
}

}  // namespace ins_preintegration

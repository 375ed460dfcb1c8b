// RTS smoother over the error-state filter's step records: on a linear model with time-varying
// F (irregular time steps) and measurement gaps it equals the batch least-squares solution of
// the whole run, means and covariances; the smoothed covariance is never above the filtered one.
// For a model that declares its transition's block pattern (the 20-state INS), the transition
// a record keeps, composed block-sparse, equals the dense product of the steps' F. A state held
// by construction (zero variance, zero noise) is passed through and the rest smoothed as
// without it.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <iostream>
#include <vector>

#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/filters/rts.hpp"
#include "ctxfuse/models/ins_augment.hpp"
#include "ctxfuse/models/ins_nav.hpp"
#include "ctxfuse/sim/random.hpp"

namespace {
using namespace ctxfuse;

/// Constant velocity on a line, white-acceleration noise: F and Q change with every dt.
struct ConstantVelocity {
  using State = Vector<2>;
  using Input = NoInput;
  static constexpr int dim = 2;
  double accel_density = 0.3;
  static SquareMatrix<2> transition(double dt) {
    SquareMatrix<2> F;
    F << 1.0, dt, 0.0, 1.0;
    return F;
  }
  State predict(const State& x, const Input&, double dt, SquareMatrix<2>* F) const {
    if (F) *F = transition(dt);
    return transition(dt) * x;
  }
  SquareMatrix<2> noise(const State&, const Input&, double dt) const {
    const double q = accel_density * accel_density;
    SquareMatrix<2> Q;
    Q << q * dt * dt * dt / 3.0, q * dt * dt / 2.0, q * dt * dt / 2.0, q * dt;
    return Q;
  }
  State inject(const State& x, const Vector<2>& dx) const { return x + dx; }
  Vector<2> difference(const State& a, const State& b) const { return a - b; }
};

struct Position {
  static constexpr int dim = 1;
  double sigma = 0.5;
  Vector<1> predict(const Vector<2>& x, Matrix<1, 2>* H) const {
    if (H) *H << 1.0, 0.0;
    return Vector<1>(x(0));
  }
  SquareMatrix<1> noise(const Vector<2>&) const { return SquareMatrix<1>(sigma * sigma); }
};

struct ForwardRun {
  std::vector<double> dt;            // dt[k] from epoch k-1 to k (dt[0] unused)
  std::vector<bool> measured;
  std::vector<double> z;
  RtsRecorder<ConstantVelocity> rec;
  std::vector<eskf::Belief<ConstantVelocity>> filtered;
};

ForwardRun forward(int epochs) {
  ForwardRun r;
  const ConstantVelocity m;
  const Position h;
  sim::Rng rng(5);
  eskf::Belief<ConstantVelocity> b;
  b.nominal << 1.0, 0.5;
  b.cov << 4.0, 0.5, 0.5, 1.0;
  r.rec.reserve(static_cast<std::size_t>(epochs));
  r.rec.start(0.0, b);
  r.filtered.push_back(b);
  r.dt.push_back(0.0);
  r.measured.push_back(false);
  r.z.push_back(0.0);
  double t = 0.0;
  for (int k = 1; k < epochs; ++k) {
    const double dt = 0.05 + 0.4 * rng.uniform();  // irregular: F_k differs at every step
    t += dt;
    // Two predictions per epoch (split interval): the recorder composes their transitions.
    SquareMatrix<2> F;
    EXPECT_TRUE(eskf::predict(m, b, {}, 0.3 * dt, {}, &F).accepted());
    r.rec.predicted(F);
    EXPECT_TRUE(eskf::predict(m, b, {}, 0.7 * dt, {}, &F).accepted());
    r.rec.predicted(F);
    const auto prior = b;
    // Measurements with gaps: none in epochs 10-24, otherwise two of three epochs.
    const bool measure = (k < 10 || k >= 25) && k % 3 != 0;
    const double z = 1.0 + 0.5 * t + 0.3 * std::sin(t) + 0.5 * rng.normal();
    if (measure) {
      EXPECT_TRUE(eskf::update(m, h, b, Vector<1>(z)).accepted());
    }
    EXPECT_TRUE(r.rec.record(t, prior, b).accepted());
    r.filtered.push_back(b);
    r.dt.push_back(dt);
    r.measured.push_back(measure);
    r.z.push_back(z);
  }
  return r;
}

TEST(Rts, EqualsBatchLeastSquaresOnALinearModelWithTimeVaryingTransition) {
  const int K = 60;
  ForwardRun r = forward(K);
  const ConstantVelocity m;
  ASSERT_TRUE(r.rec.smooth(m).accepted());

  // Batch: minimise the prior, process and measurement terms over all 2K unknowns at once.
  const int n = 2 * K;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
  const Eigen::Matrix2d P0inv = r.filtered[0].cov.inverse();
  A.block<2, 2>(0, 0) += P0inv;
  g.segment<2>(0) += P0inv * r.filtered[0].nominal;
  for (int k = 1; k < K; ++k) {
    // The two sub-steps compose to one constant-velocity step over dt with the summed noise
    // F2 Q1 F2' + Q2 -- written out here from the model, independently of the recorder.
    const double d1 = 0.3 * r.dt[static_cast<std::size_t>(k)], d2 = 0.7 * r.dt[static_cast<std::size_t>(k)];
    const Eigen::Matrix2d F2 = ConstantVelocity::transition(d2);
    const Eigen::Matrix2d F = F2 * ConstantVelocity::transition(d1);
    const Eigen::Matrix2d Q = F2 * m.noise({}, {}, d1) * F2.transpose() + m.noise({}, {}, d2);
    Eigen::Matrix<double, 2, 4> J;
    J << -F, Eigen::Matrix2d::Identity();
    const Eigen::Matrix2d W = Q.inverse();
    A.block<4, 4>(2 * (k - 1), 2 * (k - 1)) += J.transpose() * W * J;
    if (r.measured[static_cast<std::size_t>(k)]) {
      A(2 * k, 2 * k) += 1.0 / 0.25;
      g(2 * k) += r.z[static_cast<std::size_t>(k)] / 0.25;
    }
  }
  const Eigen::MatrixXd Ainv = A.inverse();
  const Eigen::VectorXd x = Ainv * g;
  double worst_mean = 0.0, worst_cov = 0.0;
  for (int k = 0; k < K; ++k) {
    const auto& s = r.rec.records()[static_cast<std::size_t>(k)].posterior;
    worst_mean = std::max(worst_mean, (s.nominal - x.segment<2>(2 * k)).cwiseAbs().maxCoeff());
    worst_cov = std::max(worst_cov, (s.cov - Ainv.block<2, 2>(2 * k, 2 * k)).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst_mean, 1e-9);
  EXPECT_LT(worst_cov, 1e-9);
  // Smoothing changed something: in the gap the filtered and smoothed estimates differ.
  EXPECT_GT((r.rec.records()[20].posterior.nominal - r.filtered[20].nominal).norm(), 1e-3);
}

TEST(Rts, SmoothedCovarianceIsNeverAboveTheFiltered) {
  ForwardRun r = forward(80);
  ASSERT_TRUE(r.rec.smooth(ConstantVelocity{}).accepted());
  for (std::size_t k = 0; k + 1 < r.filtered.size(); ++k) {
    const Eigen::Matrix2d d = r.filtered[k].cov - r.rec.records()[k].posterior.cov;
    // The smaller eigenvalue of a symmetric 2 x 2, in closed form (mean - sqrt(mean^2 - det)
    // written as mean - hypot(half difference, off-diagonal)).
    const double min_eigenvalue = 0.5 * (d(0, 0) + d(1, 1)) - std::hypot(0.5 * (d(0, 0) - d(1, 1)), 0.5 * (d(0, 1) + d(1, 0)));
    EXPECT_GE(min_eigenvalue, -1e-12) << "epoch " << k;
    EXPECT_GT(d.trace(), 0.0) << "epoch " << k;  // every epoch but the last gains from later data
  }
  // The last epoch is the filter's own.
  EXPECT_EQ(r.filtered.back().cov, r.rec.records().back().posterior.cov);
  // Memory: one record per epoch, reported.
  EXPECT_EQ(r.rec.memory_bytes(), r.rec.records().capacity() * sizeof(RtsRecorder<ConstantVelocity>::Record));
  std::cout << "RTS records: " << r.rec.records().size() << " epochs, " << r.rec.memory_bytes() << " bytes\n";
}

/// ConstantVelocity with a third state held by construction: zero prior variance, zero process
/// noise, not in the measurement (an augmented block that is not estimated).
struct ConstantVelocityWithHeldState {
  using State = Vector<3>;
  using Input = NoInput;
  static constexpr int dim = 3;
  ConstantVelocity cv;
  State predict(const State& x, const Input& u, double dt, SquareMatrix<3>* F) const {
    SquareMatrix<2> F2;
    State out;
    out << cv.predict(x.head<2>(), u, dt, F ? &F2 : nullptr), x(2);
    if (F) {
      F->setIdentity();
      F->topLeftCorner<2, 2>() = F2;
    }
    return out;
  }
  SquareMatrix<3> noise(const State& x, const Input& u, double dt) const {
    SquareMatrix<3> Q = SquareMatrix<3>::Zero();
    Q.topLeftCorner<2, 2>() = cv.noise(x.head<2>(), u, dt);
    return Q;
  }
  State inject(const State& x, const Vector<3>& dx) const { return x + dx; }
  Vector<3> difference(const State& a, const State& b) const { return a - b; }
};

struct PositionOfThree {
  static constexpr int dim = 1;
  Vector<1> predict(const Vector<3>& x, Matrix<1, 3>* H) const {
    if (H) *H << 1.0, 0.0, 0.0;
    return Vector<1>(x(0));
  }
  SquareMatrix<1> noise(const Vector<3>&) const { return SquareMatrix<1>(0.25); }
};

// The held state makes every prior covariance singular; the smoother leaves it as it is and
// smooths the others exactly as the model without it does.
TEST(Rts, AStateHeldByConstructionIsLeftAsItIsAndTheRestSmoothedAsWithoutIt) {
  const ConstantVelocity m2;
  const ConstantVelocityWithHeldState m3;
  eskf::Belief<ConstantVelocity> b2;
  eskf::Belief<ConstantVelocityWithHeldState> b3;
  b2.nominal << 1.0, 0.5;
  b2.cov << 4.0, 0.5, 0.5, 1.0;
  b3.nominal << 1.0, 0.5, 0.7;
  b3.cov.setZero();
  b3.cov.topLeftCorner<2, 2>() = b2.cov;
  RtsRecorder<ConstantVelocity> r2;
  RtsRecorder<ConstantVelocityWithHeldState> r3;
  r2.start(0.0, b2);
  r3.start(0.0, b3);
  sim::Rng rng(9);
  double t = 0.0;
  Vector<3> filtered10 = Vector<3>::Zero();
  for (int k = 1; k < 40; ++k) {
    const double dt = 0.05 + 0.4 * rng.uniform();
    t += dt;
    SquareMatrix<2> F2;
    SquareMatrix<3> F3;
    ASSERT_TRUE(eskf::predict(m2, b2, {}, dt, {}, &F2).accepted());
    ASSERT_TRUE(eskf::predict(m3, b3, {}, dt, {}, &F3).accepted());
    r2.predicted(F2);
    r3.predicted(F3);
    const auto p2 = b2;
    const auto p3 = b3;
    if (k % 4 != 0) {
      const Vector<1> z(1.0 + 0.5 * t + 0.5 * rng.normal());
      ASSERT_TRUE(eskf::update(m2, Position{}, b2, z).accepted());
      ASSERT_TRUE(eskf::update(m3, PositionOfThree{}, b3, z).accepted());
    }
    ASSERT_TRUE(r2.record(t, p2, b2).accepted());
    ASSERT_TRUE(r3.record(t, p3, b3).accepted());
    if (k == 10) filtered10 = b3.nominal;
  }
  ASSERT_EQ(b3.cov(2, 2), 0.0);  // the forward pass kept it held
  ASSERT_TRUE(r2.smooth(m2).accepted());
  ASSERT_TRUE(r3.smooth(m3).accepted());
  double worst = 0.0;
  for (std::size_t k = 0; k < r2.records().size(); ++k) {
    const auto& s2 = r2.records()[k].posterior;
    const auto& s3 = r3.records()[k].posterior;
    worst = std::max(worst, (s3.nominal.head<2>() - s2.nominal).cwiseAbs().maxCoeff());
    worst = std::max(worst, (s3.cov.topLeftCorner<2, 2>() - s2.cov).cwiseAbs().maxCoeff());
    EXPECT_EQ(s3.nominal(2), 0.7);
    EXPECT_TRUE(s3.cov.row(2).isZero(0.0));
  }
  EXPECT_LT(worst, 1e-12);
  // Smoothing did act on the others.
  EXPECT_GT((r3.records()[10].posterior.nominal - filtered10).norm(), 1e-3);
}

// A zero variance whose row is not zero is not a held state: the covariance is not positive
// semi-definite and the pass refuses it, leaving the records as filtered.
TEST(Rts, AZeroVarianceWithCrossCovarianceIsRefused) {
  const ConstantVelocityWithHeldState m3;
  eskf::Belief<ConstantVelocityWithHeldState> b;
  b.nominal.setZero();
  b.cov.setIdentity();
  RtsRecorder<ConstantVelocityWithHeldState> rec;
  rec.start(0.0, b);
  auto bad = b;
  bad.cov(2, 2) = 0.0;
  bad.cov(0, 2) = bad.cov(2, 0) = 0.1;
  ASSERT_TRUE(rec.record(1.0, bad, b).accepted());
  EXPECT_EQ(rec.smooth(m3).problem, Problem::covariance_not_positive_definite);
  EXPECT_EQ(rec.records()[0].posterior.cov, b.cov);
}

// The rule of filters/rts_gain.hpp, the same as the fixed-lag ring's: a second update at the
// newest epoch's time with no prediction since joins it (posterior replaced, prior kept);
// after a prediction, or before the newest epoch, it is refused and the records stay.
TEST(Rts, JoinsASecondUpdateAtTheSameTimeAndRefusesAnEpochThatGoesBack) {
  RtsRecorder<ConstantVelocity> rec;
  eskf::Belief<ConstantVelocity> b;
  b.nominal.setZero();
  b.cov.setIdentity();
  EXPECT_EQ(rec.record(1.0, b, b).problem, Problem::time_not_set);
  rec.start(1.0, b);
  EXPECT_EQ(rec.record(0.5, b, b).problem, Problem::out_of_order_time);
  EXPECT_TRUE(rec.record(2.0, b, b).accepted());
  ASSERT_EQ(rec.records().size(), 2u);
  eskf::Belief<ConstantVelocity> second = b;
  second.nominal(0) = 3.0;
  second.cov *= 0.5;
  EXPECT_TRUE(rec.record(2.0, b, second).accepted());
  ASSERT_EQ(rec.records().size(), 2u);
  EXPECT_EQ(rec.records().back().posterior.nominal, second.nominal);
  EXPECT_EQ(rec.records().back().posterior.cov, second.cov);
  EXPECT_EQ(rec.records().back().prior.cov, b.cov);
  rec.predicted(SquareMatrix<ConstantVelocity::dim>::Identity() * 1.5);
  EXPECT_EQ(rec.record(2.0, b, b).problem, Problem::out_of_order_time);
  EXPECT_EQ(rec.records().size(), 2u);
  EXPECT_EQ(rec.records().back().posterior.nominal, second.nominal);
}

TEST(Rts, BlockSparseTransitionEqualsTheDenseProduct) {
  using Nav20 = models::Augmented<models::InsNavModel<models::FullStrapdown>, StateBlock<"mount", 2>, StateBlock<"lever", 3>>;
  using L = Nav20::ErrorLayout;
  constexpr auto pat = Nav20::transition_blocks;
  static_assert(decltype(pat)::layout::size == 20);
  sim::Rng rng(11);
  // A random F with the declared pattern: its identity blocks identity, diagonal blocks
  // diagonal, zero outside it.
  auto random_f = [&] {
    SquareMatrix<20> F = SquareMatrix<20>::Zero();
    for (std::size_t k = 0; k < pat.size; ++k) {
      const auto rb = static_cast<std::size_t>(pat.row[k]), cb = static_cast<std::size_t>(pat.col[k]);
      const int r0 = L::offsets[rb], rs = L::sizes[rb], c0 = L::offsets[cb], cs = L::sizes[cb];
      for (int i = 0; i < rs; ++i)
        for (int j = 0; j < cs; ++j) {
          const bool on_diagonal = i == j;
          if (pat.kind[k] == BlockKind::identity) F(r0 + i, c0 + j) = on_diagonal ? 1.0 : 0.0;
          else if (pat.kind[k] == BlockKind::diagonal) F(r0 + i, c0 + j) = on_diagonal ? 1.0 + 0.1 * rng.normal() : 0.0;
          else F(r0 + i, c0 + j) = (on_diagonal && rb == cb ? 1.0 : 0.0) + 0.1 * rng.normal();
        }
    }
    return F;
  };
  RtsRecorder<Nav20> rec;
  eskf::Belief<Nav20> b{};
  b.cov.setIdentity();
  rec.start(0.0, b);
  SquareMatrix<20> dense = SquareMatrix<20>::Identity();
  for (int k = 0; k < 7; ++k) {
    const SquareMatrix<20> F = random_f();
    rec.predicted(F);
    dense = (F * dense).eval();
  }
  ASSERT_TRUE(rec.record(1.0, b, b).accepted());
  const SquareMatrix<20>& phi = rec.records().back().transition;
  EXPECT_LE((phi - dense).cwiseAbs().maxCoeff(), 1e-12 * dense.cwiseAbs().maxCoeff()) << (phi - dense).cwiseAbs().maxCoeff();
  EXPECT_GT((dense - SquareMatrix<20>::Identity()).cwiseAbs().maxCoeff(), 0.1);  // the steps did compose
}

}  // namespace


// A restart (a filter that lost its state and started again, e.g. an INS re-aligned after an
// IMU gap) splits the run: smoothing the whole equals smoothing the two runs apart, and the
// epoch before the restart keeps its filtered belief. Recorded as an ordinary epoch instead,
// the later run's data would reach back across it.
TEST(Rts, ARestartSmoothsTheRunsBeforeAndAfterItApart) {
  const ForwardRun r = forward(80);
  const auto& R = r.rec.records();
  eskf::Belief<ConstantVelocity> fresh = R[40].posterior;
  fresh.nominal += Vector<2>(3.0, -1.0);
  fresh.cov *= 3.0;
  RtsRecorder<ConstantVelocity> whole, first, second, linked;
  whole.start(R[0].t, R[0].posterior);
  first.start(R[0].t, R[0].posterior);
  linked.start(R[0].t, R[0].posterior);
  for (std::size_t k = 1; k < R.size(); ++k) {
    if (k == 40) {
      ASSERT_TRUE(whole.restart(R[k].t, fresh).accepted());
      second.start(R[k].t, fresh);
      linked.predicted(R[k].transition);
      ASSERT_TRUE(linked.record(R[k].t, fresh, fresh).accepted());
      continue;
    }
    for (RtsRecorder<ConstantVelocity>* rec : {&whole, k < 40 ? &first : &second, &linked}) {
      rec->predicted(R[k].transition);
      ASSERT_TRUE(rec->record(R[k].t, R[k].prior, R[k].posterior).accepted());
    }
  }
  EXPECT_FALSE(whole.restart(R.back().t, fresh).accepted());  // time must advance
  for (auto* rec : {&whole, &first, &second, &linked}) ASSERT_TRUE(rec->smooth(ConstantVelocity{}).accepted());
  ASSERT_EQ(whole.records().size(), R.size());
  for (std::size_t k = 0; k < R.size(); ++k) {
    const auto& w = whole.records()[k].posterior;
    const auto& apart = k < 40 ? first.records()[k].posterior : second.records()[k - 40].posterior;
    EXPECT_LT((w.nominal - apart.nominal).norm(), 1e-12) << k;
    EXPECT_LT((w.cov - apart.cov).norm(), 1e-12) << k;
  }
  EXPECT_EQ(whole.records()[39].posterior.cov, R[39].posterior.cov);
  EXPECT_GT((linked.records()[39].posterior.nominal - whole.records()[39].posterior.nominal).norm(), 1e-3);
}

// The block-tridiagonal normal equations, their block Cholesky solve, the marginal
// covariance of the last state and the Schur-complement marginalisation, each against the
// same quantity computed plainly with dense Eigen from the stacked Jacobian; and an EKF
// update against one Gauss-Newton step on the same factors.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <vector>

#include "ctxfuse/core/block_tridiagonal.hpp"
#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/factors.hpp"
#include "ctxfuse/models/averaged_range.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/models/linear.hpp"

namespace {
using namespace ctxfuse;
using PV3 = Layout<StateBlock<"p", 3>, StateBlock<"v", 3>>;
using Range = models::RangeToPoint<PV3, 3>;
using Cv = models::ConstantVelocity<PV3, 3>;
constexpr int N = 6;

/// A chain of n states with a prior on the first, a constant-velocity factor between
/// neighbours and two ranges on every state, as stacked dense rows (A, r) and as the factors.
struct Chain {
  int n = 0;
  std::vector<Vector<N>> x;
  PriorFactor<N> prior;
  std::vector<MotionFactor<Cv>> motion;                         // motion[i]: i -> i + 1
  std::vector<std::vector<MeasurementFactor<N, Range>>> ranges;  // per state

  explicit Chain(int states) : n(states) {
    Cv cv;
    cv.accel_psd = 0.5;
    Gaussian<N> g;
    g.mean << 0, 0, 1, 2, 0.5, 0;
    g.cov.diagonal() << 4, 4, 1, 1, 1, 0.25;
    EXPECT_TRUE(make_prior_factor(g, prior));
    Vector<N> truth = g.mean;
    const Vector<3> anchors[] = {{10, 0, 3}, {0, 10, 2}, {-8, -4, 4}};
    for (int i = 0; i < n; ++i) {
      if (i > 0) {
        MotionFactor<Cv> m;
        EXPECT_TRUE(make_motion_factor(cv, NoInput{}, 0.2, truth, m));
        motion.push_back(m);
        truth = cv.predict(truth, {}, 0.2, nullptr);
      }
      Vector<N> guess = truth;
      guess.head<3>() += Vector<3>(0.3, -0.2, 0.1) * (1 + i % 2);
      x.push_back(guess);
      ranges.emplace_back();
      for (int a = 0; a < 2; ++a) {
        Range r;
        r.anchor = anchors[(i + a) % 3];
        r.sigma = 0.1;
        MeasurementFactor<N, Range> f;
        EXPECT_TRUE(make_measurement_factor<N>(r, Vector<1>((truth.head<3>() - r.anchor).norm() + 0.05), truth, f));
        ranges.back().push_back(f);
      }
    }
  }

  template <int K>
  void fill(BlockTridiagonal<N, K>& sys) const {
    sys.reset(n);
    EXPECT_TRUE(sys.add(prior, 0, x[0]));
    for (int i = 0; i < n; ++i) {
      for (const auto& f : ranges[static_cast<std::size_t>(i)]) EXPECT_TRUE(sys.add(f, i, x[static_cast<std::size_t>(i)]));
      if (i > 0) {
        const auto k = static_cast<std::size_t>(i);
        EXPECT_TRUE(sys.add(motion[k - 1], i - 1, x[k - 1], x[k]));
      }
    }
  }

  /// Stacked whitened Jacobian and residual of every factor, written out plainly.
  void dense(Eigen::MatrixXd& A, Eigen::VectorXd& r) const {
    const int rows = N + 2 * n + N * (n - 1);
    A = Eigen::MatrixXd::Zero(rows, N * n);
    r = Eigen::VectorXd::Zero(rows);
    int row = 0;
    Matrix<N, N> Jp;
    r.segment<N>(row) = prior.evaluate(x[0], &Jp);
    A.block<N, N>(row, 0) = Jp;
    row += N;
    for (int i = 0; i < n; ++i) {
      for (const auto& f : ranges[static_cast<std::size_t>(i)]) {
        Matrix<1, N> J;
        r(row) = f.evaluate(x[static_cast<std::size_t>(i)], &J)(0);
        A.block<1, N>(row, N * i) = J;
        ++row;
      }
      if (i > 0) {
        SquareMatrix<N> Ja, Jb;
        r.segment<N>(row) = motion[static_cast<std::size_t>(i - 1)].evaluate(x[static_cast<std::size_t>(i - 1)], x[static_cast<std::size_t>(i)], &Ja, &Jb);
        A.block<N, N>(row, N * (i - 1)) = Ja;
        A.block<N, N>(row, N * i) = Jb;
        row += N;
      }
    }
  }
};

/// H = A' A and g = A' r from the stacked rows, plainly.
struct Dense {
  Eigen::MatrixXd A, H;
  Eigen::VectorXd r, g;
  explicit Dense(const Chain& chain) {
    chain.dense(A, r);
    H = A.transpose() * A;
    g = A.transpose() * r;
  }
};

TEST(WindowAlgebra, NormalEquationsSolveAndLastCovarianceEqualDense) {
  Chain chain(5);
  BlockTridiagonal<N, 8> sys;
  chain.fill(sys);
  const Dense d(chain);
  const Eigen::MatrixXd& H = d.H;
  const Eigen::VectorXd& g = d.g;
  for (int i = 0; i < chain.n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    EXPECT_LT((sys.diagonal[k] - H.block<N, N>(N * i, N * i)).cwiseAbs().maxCoeff(), 1e-9 * H.cwiseAbs().maxCoeff());
    EXPECT_LT((sys.gradient[k] - g.segment<N>(N * i)).cwiseAbs().maxCoeff(), 1e-9 * g.cwiseAbs().maxCoeff());
    if (i + 1 < chain.n) {
      EXPECT_LT((sys.lower[k] - H.block<N, N>(N * (i + 1), N * i)).cwiseAbs().maxCoeff(), 1e-9 * H.cwiseAbs().maxCoeff());
    }
  }
  EXPECT_NEAR(sys.cost, 0.5 * d.r.squaredNorm(), 1e-12 * d.r.squaredNorm());

  BlockTridiagonalCholesky<N, 8> chol;
  ASSERT_EQ(chol.factorize(sys), Problem::none);
  std::array<Vector<N>, 8> b, dx;
  for (int i = 0; i < chain.n; ++i) b[static_cast<std::size_t>(i)] = -sys.gradient[static_cast<std::size_t>(i)];
  chol.solve(sys, b, dx);
  const Eigen::VectorXd dense_dx = H.ldlt().solve(-g);
  for (int i = 0; i < chain.n; ++i)
    EXPECT_LT((dx[static_cast<std::size_t>(i)] - dense_dx.segment<N>(N * i)).cwiseAbs().maxCoeff(), 1e-10);
  const Eigen::MatrixXd cov = H.inverse();
  const int last = N * (chain.n - 1);
  EXPECT_LT((chol.last_covariance() - cov.block<N, N>(last, last)).cwiseAbs().maxCoeff(), 1e-12);

  // Damped: each diagonal element scaled by (1 + lambda), as written out here.
  Eigen::MatrixXd Hd = H;
  for (int j = 0; j < Hd.rows(); ++j) Hd(j, j) += 0.3 * H(j, j);
  ASSERT_EQ(chol.factorize(sys, 0.3), Problem::none);
  chol.solve(sys, b, dx);
  const Eigen::VectorXd damped = Hd.ldlt().solve(-g);
  for (int i = 0; i < chain.n; ++i)
    EXPECT_LT((dx[static_cast<std::size_t>(i)] - damped.segment<N>(N * i)).cwiseAbs().maxCoeff(), 1e-10);
}

TEST(WindowAlgebra, MarginalisationEqualsDenseSchurComplement) {
  Chain chain(2);
  BlockTridiagonal<N, 2> sys;
  chain.fill(sys);
  const Dense d(chain);
  const Eigen::MatrixXd H00 = d.H.topLeftCorner(N, N), H01 = d.H.topRightCorner(N, N), H11 = d.H.bottomRightCorner(N, N);
  const Eigen::MatrixXd Lambda = H11 - H01.transpose() * H00.inverse() * H01;
  const Eigen::VectorXd eta = d.g.tail(N) - H01.transpose() * H00.inverse() * d.g.head(N);
  const Eigen::VectorXd mean = chain.x[1] - Lambda.inverse() * eta;

  PriorFactor<N> prior;
  ASSERT_TRUE(marginalize_first(sys, chain.x[1], prior));
  EXPECT_LT((prior.W.transpose() * prior.W - Lambda).cwiseAbs().maxCoeff(), 1e-9 * Lambda.cwiseAbs().maxCoeff());
  EXPECT_LT((prior.mean - mean).cwiseAbs().maxCoeff(), 1e-10);
  // The dense joint solve gives x1's mean too: the quadratic model minimised over both states.
  const Eigen::VectorXd joint = d.H.ldlt().solve(-d.g);
  EXPECT_LT((prior.mean - (chain.x[1] + joint.tail(N))).cwiseAbs().maxCoeff(), 1e-10);
}

TEST(WindowAlgebra, IndefiniteBlocksGiveAStatusAndLeaveThePriorAlone) {
  Chain chain(2);
  BlockTridiagonal<N, 2> sys;
  sys.reset(2);
  // A range alone on state 0: rank one, H00 singular.
  ASSERT_TRUE(sys.add(chain.ranges[0][0], 0, chain.x[0]));
  ASSERT_TRUE(sys.add(chain.motion[0], 0, chain.x[0], chain.x[1]));
  PriorFactor<N> prior;
  prior.mean.setConstant(7.0);
  const Status s = marginalize_first(sys, chain.x[1], prior);
  EXPECT_EQ(s.outcome, Outcome::numerical_failure);
  EXPECT_EQ(s.problem, Problem::system_not_positive_definite);
  EXPECT_EQ(prior.mean, Vector<N>::Constant(7.0));
  BlockTridiagonalCholesky<N, 2> chol;
  EXPECT_EQ(chol.factorize(sys), Problem::system_not_positive_definite);
  sys.diagonal[1](2, 2) = std::nan("");
  EXPECT_EQ(chol.factorize(sys, 1.0), Problem::system_not_positive_definite);
}

/// A random symmetric positive definite M x M with eigenvalues spread log-uniformly over
/// `decades` decades (condition number 10^decades).
template <int M>
SquareMatrix<M> random_spd(int seed, double decades) {
  std::srand(static_cast<unsigned>(seed));
  // The orthogonal factor from a dynamic-size QR: one instantiation for every M (a fixed-size
  // HouseholderQR costs g++ some 7 s of compile time per size).
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(Eigen::MatrixXd::Random(M, M));
  const SquareMatrix<M> Q = Eigen::MatrixXd(qr.householderQ());
  Vector<M> eig;
  for (int i = 0; i < M; ++i) eig(i) = std::pow(10.0, decades * (M > 1 ? double(i) / (M - 1) : 0.0) - 2.0);
  SquareMatrix<M> S = Q * eig.asDiagonal() * Q.transpose();
  symmetrize(S);
  return S;
}

template <int M>
void expect_spd_inverse_matches_eigen() {
  SCOPED_TRACE(M);
  for (int seed = 1; seed <= 20; ++seed) {
    const double decades = 0.5 * (seed % 13);  // condition numbers 1 .. 1e6
    const SquareMatrix<M> S = random_spd<M>(seed, decades);
    const SquareMatrix<M> ref = S.llt().solve(SquareMatrix<M>::Identity());
    SquareMatrix<M> inv, inv_ldl;
    ASSERT_TRUE(spd_inverse<M>(S, inv)) << seed;
    ASSERT_TRUE(detail::spd_inverse_ldl<M>(S, inv_ldl)) << seed;
    // Both are backward stable: errors of order cond * eps relative to the inverse.
    const double tol = 50.0 * std::pow(10.0, decades) * 2.2e-16 * ref.cwiseAbs().maxCoeff();
    EXPECT_LT((inv - ref).cwiseAbs().maxCoeff(), tol) << seed;
    EXPECT_LT((inv_ldl - ref).cwiseAbs().maxCoeff(), tol) << seed;
    EXPECT_EQ(inv, inv.transpose()) << seed;
  }
  // Not positive definite although every diagonal entry is positive (I with one pair of
  // off-diagonal entries 1.5: eigenvalues -0.5 and 2.5), each pair in turn: the pivots decide.
  SquareMatrix<M> out;
  for (int i = 1; i < M; ++i)
    for (int j = 0; j < i; ++j) {
      SquareMatrix<M> indefinite = SquareMatrix<M>::Identity();
      indefinite(i, j) = indefinite(j, i) = 1.5;
      EXPECT_FALSE(spd_inverse<M>(indefinite, out)) << i << "," << j;
      EXPECT_FALSE(detail::spd_inverse_ldl<M>(indefinite, out)) << i << "," << j;
    }
  EXPECT_FALSE(spd_inverse<M>(-SquareMatrix<M>::Identity(), out));
  EXPECT_FALSE(spd_inverse<M>(SquareMatrix<M>::Zero(), out));
  // NaN or Inf in any entry of the lower triangle (the part read).
  for (int i = 0; i < M; ++i)
    for (int j = 0; j <= i; ++j)
      for (double bad : {std::nan(""), std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()}) {
        SquareMatrix<M> S = random_spd<M>(5, 2.0);
        S(i, j) = S(j, i) = bad;
        EXPECT_FALSE(spd_inverse<M>(S, out)) << i << "," << j << " " << bad;
        EXPECT_FALSE(detail::spd_inverse_ldl<M>(S, out)) << i << "," << j << " " << bad;
      }
}

TEST(WindowAlgebra, SpdInverseEqualsEigenAndRefusesWhatIsNotPositiveDefinite) {
  // 4 x 4 takes the 2 x 2 block formula (the UWB smoother's state), 8 x 8 the 4 x 4 block
  // formula (the planar IMU state), the others LDL'.
  expect_spd_inverse_matches_eigen<1>();
  expect_spd_inverse_matches_eigen<2>();
  expect_spd_inverse_matches_eigen<3>();
  expect_spd_inverse_matches_eigen<4>();
  expect_spd_inverse_matches_eigen<6>();
  expect_spd_inverse_matches_eigen<8>();
}

/// One EKF update of `belief` with `model` against one Gauss-Newton step on the prior factor
/// and the measurement factor of the same model, solved by the window's block Cholesky.
template <int Dim, class Model>
void expect_ekf_update_is_one_gauss_newton_step(const Model& model, Gaussian<Dim> belief, const Vector<1>& z, int trial) {
  PriorFactor<Dim> prior;
  MeasurementFactor<Dim, Model> meas;
  ASSERT_TRUE(make_prior_factor(belief, prior));
  ASSERT_TRUE(make_measurement_factor<Dim>(model, z, belief.mean, meas));
  BlockTridiagonal<Dim, 1> sys;
  sys.reset(1);
  ASSERT_TRUE(sys.add(prior, 0, belief.mean));
  ASSERT_TRUE(sys.add(meas, 0, belief.mean));
  BlockTridiagonalCholesky<Dim, 1> chol;
  ASSERT_EQ(chol.factorize(sys), Problem::none);
  std::array<Vector<Dim>, 1> b{-sys.gradient[0]}, dx;
  chol.solve(sys, b, dx);

  ASSERT_TRUE(ekf::update<Dim>(model, belief, z));
  EXPECT_LT(((belief.mean - prior.mean) - dx[0]).cwiseAbs().maxCoeff(), 1e-12) << trial;
  EXPECT_LT((belief.cov - chol.last_covariance()).cwiseAbs().maxCoeff(), 1e-12) << trial;
  EXPECT_GT(dx[0].norm(), 1e-2);  // the update moved the state: the equality is not 0 = 0
}

TEST(WindowAlgebra, EkfUpdateEqualsOneGaussNewtonStep) {
  Range range;
  range.anchor = {12.0, -4.0, 3.0};
  range.sigma = 0.2;
  for (int trial = 0; trial < 3; ++trial) {
    Gaussian<N> belief;
    belief.mean << 1.0 + trial, 2.0, 0.5, 1.5, -0.5, 0.0;
    SquareMatrix<N> B = SquareMatrix<N>::Random();
    belief.cov = 0.1 * B * B.transpose() + 0.2 * SquareMatrix<N>::Identity();
    expect_ekf_update_is_one_gauss_newton_step<N>(range, belief, Vector<1>(13.0 + trial), trial);
  }
}

// The same for the averaged, biased range of the self-calibrating UWB EKF (7 states: p, v and
// three anchor biases), whose row touches position, velocity and one bias.
TEST(WindowAlgebra, EkfUpdateEqualsOneGaussNewtonStepForTheAveragedBiasedRange) {
  using PVB = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>, StateBlock<"b", 3>>;
  models::AveragedRangeWithBias<PVB> avg;
  avg.anchor = {2.5775, 0.87, 1.97};
  avg.tag_height = 1.0;
  avg.samples = 3;
  avg.period_s = 0.1;
  avg.sigma = 0.1;
  for (int trial = 0; trial < 3; ++trial) {
    avg.bias_slot = trial;
    Gaussian<7> belief;
    belief.mean << 20.0 + trial, -3.0, 0.8, -0.2, 0.05, -0.02, 0.01;
    SquareMatrix<7> B = SquareMatrix<7>::Random();
    belief.cov = 0.1 * B * B.transpose() + 0.05 * SquareMatrix<7>::Identity();
    expect_ekf_update_is_one_gauss_newton_step<7>(avg, belief, Vector<1>(19.0 + trial), trial);
  }
}

}  // namespace

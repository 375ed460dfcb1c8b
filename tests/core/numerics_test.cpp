#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>

#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/policies/gating.hpp"

namespace {
using namespace ctxfuse;

TEST(ChiSquare, QuantilesMatchStatisticalTables) {
  // Standard table values (e.g. NIST/SEMATECH e-Handbook, section 1.3.6.7.4).
  EXPECT_NEAR(chi_square_quantile(0.95, 1), 3.841, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.95, 2), 5.991, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.95, 3), 7.815, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.99, 3), 11.345, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.99, 10), 23.209, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.05, 4), 0.711, 1e-3);
  // dof 2 has the closed form -2 ln(1 - p).
  for (double p : {0.1, 0.5, 0.9, 0.999, 0.999999})
    EXPECT_NEAR(chi_square_quantile(p, 2), -2.0 * std::log(1.0 - p), 1e-9 * (1.0 - 2.0 * std::log(1.0 - p)));
  // dof 1: P(X <= x) = erf(sqrt(x / 2)).
  for (double x : {0.01, 0.5, 3.0, 20.0}) EXPECT_NEAR(chi_square_cdf(x, 1), std::erf(std::sqrt(x / 2.0)), 1e-13);
}

TEST(ChiSquare, GateCachesTheQuantiles) {
  const ChiSquareGate gate(0.99);
  for (int dof = 1; dof <= 20; ++dof) EXPECT_DOUBLE_EQ(gate.threshold(dof), chi_square_quantile(0.99, dof));
  EXPECT_TRUE(std::isinf(NoGate{}.threshold(3)));
}

TEST(Numerics, JosephEqualsShortFormAtTheOptimalGain) {
  SquareMatrix<4> A = SquareMatrix<4>::Random();
  const SquareMatrix<4> P = A * A.transpose() + SquareMatrix<4>::Identity();
  Matrix<2, 4> H = Matrix<2, 4>::Random();
  const SquareMatrix<2> R = Vector<2>(0.3, 0.7).asDiagonal();
  const SquareMatrix<2> S = H * P * H.transpose() + R;
  const Matrix<4, 2> K = P * H.transpose() * S.inverse();
  const SquareMatrix<4> joseph = joseph_update<4, 2>(P, K, H, R);
  const SquareMatrix<4> short_form = (SquareMatrix<4>::Identity() - K * H) * P;
  EXPECT_LT((joseph - short_form).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(joseph, joseph.transpose());  // exactly symmetric

  // Off the optimal gain the Joseph form stays a covariance; check against the definition
  // Cov[(I-KH) e + K v] written out plainly.
  const Matrix<4, 2> K_bad = 1.7 * K;
  const SquareMatrix<4> I_KH = SquareMatrix<4>::Identity() - K_bad * H;
  const SquareMatrix<4> expected = I_KH * P * I_KH.transpose() + K_bad * R * K_bad.transpose();
  EXPECT_LT((joseph_update<4, 2>(P, K_bad, H, R) - expected).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Numerics, InnovationSolveGivesNisAndGaussianLogLikelihood) {
  SquareMatrix<3> S;
  S << 4, 1, 0.5, 1, 3, 0.2, 0.5, 0.2, 2;
  const Vector<3> y(0.3, -1.2, 0.8);
  const InnovationSolve<3> solve(S);
  ASSERT_TRUE(solve.ok);
  const double nis = y.transpose() * S.inverse() * y;
  EXPECT_NEAR(solve.nis(y), nis, 1e-13);
  const double ll = -0.5 * nis - 0.5 * std::log(S.determinant()) - 1.5 * std::log(2.0 * std::numbers::pi);
  EXPECT_NEAR(solve.log_likelihood(solve.nis(y)), ll, 1e-12);

  SquareMatrix<3> indefinite = S;
  indefinite(2, 2) = -1.0;
  EXPECT_FALSE(InnovationSolve<3>(indefinite).ok);
  EXPECT_FALSE(is_positive_definite(indefinite));
  EXPECT_TRUE(is_positive_definite(S));
}

// Plain dynamic-size references, written out from the definitions.
Eigen::MatrixXd random_spd(int n, unsigned seed) {
  std::srand(seed);
  const Eigen::MatrixXd A = Eigen::MatrixXd::Random(n, n);
  return A * A.transpose() + 0.5 * Eigen::MatrixXd::Identity(n, n);
}

TEST(Numerics, FusedJosephEqualsTextbookJosephForAnyGain) {
  constexpr int N = 15, M = 3;
  const Eigen::MatrixXd P = random_spd(N, 7);
  std::srand(11);
  const Eigen::MatrixXd H = Eigen::MatrixXd::Random(M, N);
  const Eigen::MatrixXd R = random_spd(M, 13);
  const Eigen::MatrixXd S = H * P * H.transpose() + R;
  const Eigen::MatrixXd K_opt = P * H.transpose() * S.inverse();
  for (const double scale : {1.0, 0.6, 1.9}) {
    // Off-optimal gains too (scaled, and perturbed so that K S - P H' has no special form).
    Eigen::MatrixXd K = scale * K_opt;
    K(4, 1) += 0.05 * (scale - 1.0);
    const Eigen::MatrixXd I_KH = Eigen::MatrixXd::Identity(N, N) - K * H;
    const Eigen::MatrixXd expected = I_KH * P * I_KH.transpose() + K * R * K.transpose();
    const SquareMatrix<N> got = joseph_update_expanded<N, M>(SquareMatrix<N>(P), Matrix<N, M>(K),
                                                             Matrix<N, M>(P * H.transpose()), SquareMatrix<M>(S));
    EXPECT_LT((got - expected).cwiseAbs().maxCoeff(), 1e-12) << "gain scale " << scale;
    EXPECT_EQ(got, got.transpose());

    // The lower-only form writes nothing above the diagonal.
    SquareMatrix<N> lower = SquareMatrix<N>::Constant(-123.0);
    joseph_update_expanded_lower<N, M>(SquareMatrix<N>(P), Matrix<N, M>(K), Matrix<N, M>(P * H.transpose()),
                                       SquareMatrix<M>(S), lower);
    for (int j = 0; j < N; ++j)
      for (int i = 0; i < N; ++i) {
        if (i < j) EXPECT_EQ(lower(i, j), -123.0);
        else EXPECT_NEAR(lower(i, j), expected(i, j), 1e-12);
      }
  }
}

TEST(Numerics, CholeskyGainEqualsExplicitInverse) {
  constexpr int N = 15;
  const Eigen::MatrixXd S3 = random_spd(3, 17);
  std::srand(19);
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(N, 3);
  const InnovationSolve<3> solve3{SquareMatrix<3>(S3)};
  ASSERT_TRUE(solve3.ok);
  EXPECT_LT((solve3.right_solve<N>(Matrix<N, 3>(B)) - B * S3.inverse()).cwiseAbs().maxCoeff(), 1e-12);
  // L L' reproduces S, and L is lower triangular.
  EXPECT_LT((solve3.L * solve3.L.transpose() - S3).cwiseAbs().maxCoeff(), 1e-13);
  EXPECT_EQ(solve3.L(0, 1), 0.0);
  EXPECT_EQ(solve3.L(0, 2), 0.0);
  EXPECT_EQ(solve3.L(1, 2), 0.0);
  const InnovationSolve<1> solve1{SquareMatrix<1>(0.09)};
  ASSERT_TRUE(solve1.ok);
  EXPECT_LT((solve1.right_solve<N>(Matrix<N, 1>(B.col(0))) - B.col(0) / 0.09).cwiseAbs().maxCoeff(), 1e-12);
  // Non-finite or non-positive pivots fail.
  SquareMatrix<3> bad = SquareMatrix<3>(S3);
  bad(2, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(InnovationSolve<3>(bad).ok);
  EXPECT_FALSE(InnovationSolve<1>(SquareMatrix<1>(0.0)).ok);
  EXPECT_FALSE(InnovationSolve<1>(SquareMatrix<1>(std::numeric_limits<double>::infinity())).ok);
}

TEST(Numerics, SymmetrizeMirrorsTheLowerTriangle) {
  SquareMatrix<3> P;
  P << 1, 2, 3, 4, 5, 6, 7, 8, 9;
  symmetrize(P);
  EXPECT_EQ(P(0, 1), 4.0);
  EXPECT_EQ(P(1, 0), 4.0);
  EXPECT_EQ(P(0, 2), 7.0);
  EXPECT_EQ(P(1, 2), 8.0);
  EXPECT_EQ(P.diagonal(), Vector<3>(1, 5, 9));
  EXPECT_EQ(P, P.transpose());
}

}  // namespace

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>

#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/so3.hpp"
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
  const policies::ChiSquareGate gate(0.99);
  for (int dof = 1; dof <= 20; ++dof) EXPECT_DOUBLE_EQ(gate.threshold(dof), chi_square_quantile(0.99, dof));
  EXPECT_TRUE(std::isinf(policies::NoGate{}.threshold(3)));
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

TEST(Numerics, SymmetrizeAndAddLowerMatchEigenTriangularViews) {
  std::srand(23);
  const SquareMatrix<15> A = SquareMatrix<15>::Random();
  SquareMatrix<15> mirrored = A;
  symmetrize(mirrored);
  SquareMatrix<15> expected = A;
  expected.triangularView<Eigen::StrictlyUpper>() = A.transpose();
  EXPECT_EQ(mirrored, expected);

  const SquareMatrix<15> Q = SquareMatrix<15>::Random();
  SquareMatrix<15> sum = A;
  add_lower(sum, Q);
  for (int j = 0; j < 15; ++j)
    for (int i = 0; i < 15; ++i) EXPECT_EQ(sum(i, j), i >= j ? A(i, j) + Q(i, j) : A(i, j)) << i << "," << j;
}

template <int N, int Options = Eigen::ColMajor>
void expect_symmetrize_matches_the_triangular_view() {
  using Mat = Eigen::Matrix<double, N, N, Options>;
  const Mat A = Mat::Random();
  Mat mirrored = A;
  symmetrize(mirrored);
  Mat expected = A;
  expected.template triangularView<Eigen::StrictlyUpper>() = A.transpose();
  EXPECT_EQ(mirrored, expected) << N << " x " << N << (Options == Eigen::RowMajor ? ", row-major" : "");
}

// Every size the straight-line path takes, the row-major fallback, and a block view.
TEST(Numerics, SymmetrizeMatchesTheTriangularViewForEverySizeAndStorage) {
  std::srand(29);
  expect_symmetrize_matches_the_triangular_view<1>();
  expect_symmetrize_matches_the_triangular_view<2>();
  expect_symmetrize_matches_the_triangular_view<8>();
  expect_symmetrize_matches_the_triangular_view<20>();
  expect_symmetrize_matches_the_triangular_view<6, Eigen::RowMajor>();
  SquareMatrix<6> big = SquareMatrix<6>::Random();
  const SquareMatrix<6> before = big;
  auto corner = big.topLeftCorner<3, 3>();
  symmetrize(corner);
  for (int j = 0; j < 6; ++j)
    for (int i = 0; i < 6; ++i)
      EXPECT_EQ(big(i, j), (i < j && j < 3) ? before(j, i) : before(i, j)) << i << "," << j;
}

TEST(Numerics, LowerMinusProductEqualsDenseFormula) {
  std::srand(29);
  const SquareMatrix<15> P(random_spd(15, 31));
  const Matrix<15, 6> A = Matrix<15, 6>::Random();
  const Matrix<15, 6> B = Matrix<15, 6>::Random();
  const Eigen::MatrixXd expected = Eigen::MatrixXd(P) - Eigen::MatrixXd(A) * Eigen::MatrixXd(B).transpose();
  SquareMatrix<15> out = SquareMatrix<15>::Constant(-5.0);
  lower_minus_product<15, 6>(P, A, B, out);
  for (int j = 0; j < 15; ++j)
    for (int i = 0; i < 15; ++i) {
      if (i < j) EXPECT_EQ(out(i, j), -5.0);
      else EXPECT_NEAR(out(i, j), expected(i, j), 1e-12 * (1.0 + std::abs(expected(i, j))));
    }
}

TEST(So3, SharedExpAndRightJacobianEqualTheSeparateOnes) {
  // Large, moderate, small (series branch of Jr only) and tiny (series branch of both) angles.
  for (const double scale : {2.5, 0.3, 1e-4, 3e-6, 1e-9}) {
    const Eigen::Vector3d phi = scale * Eigen::Vector3d(0.6, -0.48, 0.64);
    Eigen::Quaterniond q;
    Eigen::Matrix3d Jr;
    so3::exp_quat_and_right_jacobian(phi, q, Jr);
    // Reference rotation from Eigen's angle-axis, independent of so3::.
    const Eigen::Matrix3d R_ref = Eigen::AngleAxisd(phi.norm(), phi.normalized()).toRotationMatrix();
    EXPECT_LT((q.toRotationMatrix() - R_ref).cwiseAbs().maxCoeff(), 1e-14) << scale;
    EXPECT_NEAR(q.norm(), 1.0, 1e-14);
    // Reference Jr = I - a K + b K^2 with a = (1 - cos t) / t^2 and b = (t - sin t) / t^3 summed
    // as their Taylor series (no cancellation, unlike the closed forms at small t, where
    // 1 - cos t loses about half the digits; the shared form uses 2 sin^2(t/2) instead).
    const double t2 = phi.squaredNorm();
    double a = 0.0, b = 0.0, term_a = 0.5, term_b = 1.0 / 6.0;
    for (int k = 0; k < 30; ++k) {
      a += term_a;
      b += term_b;
      term_a *= -t2 / ((2.0 * k + 3.0) * (2.0 * k + 4.0));
      term_b *= -t2 / ((2.0 * k + 4.0) * (2.0 * k + 5.0));
    }
    const Eigen::Matrix3d K = so3::skew(phi);
    const Eigen::Matrix3d Jr_ref = Eigen::Matrix3d::Identity() - a * K + b * K * K;
    EXPECT_LT((Jr - Jr_ref).cwiseAbs().maxCoeff(), 2e-15) << scale;
    // The separate closed form agrees to its own cancellation error.
    EXPECT_LT((Jr - so3::right_jacobian(phi)).cwiseAbs().maxCoeff(), 1e-11) << scale;
    // Jr from its definition Exp(phi + d) = Exp(phi) Exp(Jr d), by central differences.
    if (scale > 1e-3) {
      Eigen::Matrix3d numeric;
      const double h = 1e-6;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(k);
        const Eigen::Quaterniond plus(so3::exp(phi + e)), minus(so3::exp(phi - e));
        numeric.col(k) = (so3::log(Eigen::Quaterniond(q.conjugate() * plus)) -
                          so3::log(Eigen::Quaterniond(q.conjugate() * minus))) / (2.0 * h);
      }
      EXPECT_LT((numeric - Jr).cwiseAbs().maxCoeff(), 1e-8) << scale;
    }
  }
}

}  // namespace

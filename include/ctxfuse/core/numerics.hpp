// Numerical building blocks shared by every filter: symmetrisation, the Joseph-form update,
// a Cholesky-based innovation solve with NIS and log-likelihood, and chi-square quantiles.
#pragma once

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>
#include <numbers>

#include "ctxfuse/core/types.hpp"

namespace ctxfuse {

/// True when no element is NaN or Inf. x * 0 is 0 for finite x and NaN otherwise, so one
/// vectorised multiply-add pass decides; Eigen's allFinite() is not vectorised.
template <class Derived>
bool all_finite(const Eigen::DenseBase<Derived>& m) {
  return (m.derived().array() * typename Derived::Scalar(0)).sum() == typename Derived::Scalar(0);
}

/// Makes P exactly symmetric by mirroring its lower triangle onto the upper one. The two
/// triangles of a covariance computed by the filters differ only by rounding, so averaging
/// them would buy nothing and cost three times as much (strided reads of both triangles).
template <class Derived>
void symmetrize(Eigen::MatrixBase<Derived>& P) {
  P.template triangularView<Eigen::StrictlyUpper>() = P.transpose();
}

/// Joseph form P+ = (I - K H) P (I - K H)' + K R K'. Symmetric and positive semi-definite for
/// any gain, which the short form (I - K H) P is not once K is off-optimal or rounding bites.
template <int N, int M>
SquareMatrix<N> joseph_update(const SquareMatrix<N>& P, const Matrix<N, M>& K, const Matrix<M, N>& H,
                              const SquareMatrix<M>& R) {
  SquareMatrix<N> I_KH = -K * H;
  I_KH.diagonal().array() += 1.0;
  SquareMatrix<N> out = I_KH * P * I_KH.transpose();
  out.noalias() += K * R * K.transpose();
  symmetrize(out);
  return out;
}

/// The Joseph form expanded: with S = H P H' + R and PHt = P H',
///   (I - K H) P (I - K H)' + K R K' = P - K PHt' - PHt K' + K S K'
/// holds exactly for ANY gain K, so this keeps the Joseph form's first-order insensitivity to
/// gain errors while costing O(N^2 M) instead of the O(N^3) of multiplying out (I - K H).
/// (What it does not keep is the congruence structure, which guarantees semi-definiteness
/// under rounding; joseph_update above keeps it, at N^3.)
/// The result is symmetric up to rounding; callers symmetrise once, after any reset.
template <int N, int M>
SquareMatrix<N> joseph_update_expanded(const SquareMatrix<N>& P, const Matrix<N, M>& K, const Matrix<N, M>& PHt,
                                       const SquareMatrix<M>& S) {
  // Rank-M outer products: coefficient-based (lazy) products beat Eigen's blocked GEMM path
  // by a wide margin at these sizes, and allocate nothing either way.
  const SquareMatrix<N> K_PHt = K.lazyProduct(PHt.transpose());
  const Matrix<N, M> KS = K * S;
  SquareMatrix<N> out = P;
  out -= K_PHt;
  out -= K_PHt.transpose();
  out += KS.lazyProduct(K.transpose());
  return out;
}

/// Cholesky factorisation of an innovation covariance S with what the update needs from it.
template <int M>
struct InnovationSolve {
  Eigen::LLT<SquareMatrix<M>> llt;
  bool ok = false;

  explicit InnovationSolve(const SquareMatrix<M>& S) : llt(S) {
    ok = llt.info() == Eigen::Success;
    if (ok) {
      // LLT "succeeds" on some indefinite inputs that round to a tiny positive pivot;
      // a non-positive or non-finite diagonal of L is a failure all the same.
      const auto d = llt.matrixLLT().diagonal();
      ok = d.allFinite() && (d.array() > 0.0).all();
    }
  }

  /// y' S^-1 y
  double nis(const Vector<M>& y) const { return y.dot(llt.solve(y)); }
  double log_det() const {
    // One logarithm of the product of the pivots; the sum of logs only when the product
    // leaves the double range (it cannot for innovation covariances of sane units).
    const auto d = llt.matrixLLT().diagonal();
    const double prod = d.prod();
    if (prod > 1e-150 && prod < 1e150) return 2.0 * std::log(prod);
    return 2.0 * d.array().log().sum();
  }
  /// log N(y; 0, S)
  double log_likelihood(double nis_value) const {
    return -0.5 * (nis_value + log_det() + M * std::log(2.0 * std::numbers::pi));
  }
};

/// Positive definiteness through a Cholesky attempt (the cheapest complete test).
template <class Derived>
bool is_positive_definite(const Eigen::MatrixBase<Derived>& A) {
  using Mat = Eigen::Matrix<typename Derived::Scalar, Derived::RowsAtCompileTime, Derived::ColsAtCompileTime>;
  Eigen::LLT<Mat> llt(A.derived());
  if (llt.info() != Eigen::Success) return false;
  const auto d = llt.matrixLLT().diagonal();
  return d.allFinite() && (d.array() > 0.0).all();
}

namespace detail {

// Regularised lower incomplete gamma P(a, x): series below a + 1, continued fraction above
// (modified Lentz), both to double precision.
inline double regularized_gamma_p(double a, double x) {
  if (x <= 0.0) return 0.0;
  const double log_prefactor = a * std::log(x) - x - std::lgamma(a);
  if (x < a + 1.0) {
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 1000; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * 1e-17) break;
    }
    return sum * std::exp(log_prefactor);
  }
  constexpr double tiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int n = 1; n < 1000; ++n) {
    const double an = -n * (n - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-16) break;
  }
  return 1.0 - std::exp(log_prefactor) * h;
}

}  // namespace detail

/// CDF of the chi-square distribution with `dof` degrees of freedom.
inline double chi_square_cdf(double x, int dof) { return detail::regularized_gamma_p(0.5 * dof, 0.5 * x); }

/// Quantile of the chi-square distribution: the x with P(X <= x) = probability.
/// Bisection on the CDF (monotone, so it cannot diverge) to a relative 1e-13.
inline double chi_square_quantile(double probability, int dof) {
  if (!(probability > 0.0) || dof <= 0) return 0.0;
  if (!(probability < 1.0)) return std::numeric_limits<double>::infinity();
  double lo = 0.0, hi = std::max(1.0, 2.0 * dof);
  while (chi_square_cdf(hi, dof) < probability) hi *= 2.0;
  for (int i = 0; i < 200 && hi - lo > 1e-13 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (chi_square_cdf(mid, dof) < probability ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace ctxfuse

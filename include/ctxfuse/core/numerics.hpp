// Numerical building blocks shared by every filter: symmetrisation, the Joseph-form update,
// a Cholesky-based innovation solve with NIS and log-likelihood, and chi-square quantiles.
#pragma once

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>
#include <numbers>

#include "ctxfuse/core/types.hpp"

namespace ctxfuse {

template <class Derived>
void symmetrize(Eigen::MatrixBase<Derived>& P) {
  // In place, element pairs only, so that no aliasing temporary is needed.
  for (Eigen::Index j = 0; j < P.cols(); ++j)
    for (Eigen::Index i = j + 1; i < P.rows(); ++i) {
      const auto m = 0.5 * (P(i, j) + P(j, i));
      P(i, j) = m;
      P(j, i) = m;
    }
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
  double log_det() const { return 2.0 * llt.matrixLLT().diagonal().array().log().sum(); }
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

// Numerical building blocks shared by every filter: symmetrisation, the Joseph-form update,
// a Cholesky-based innovation solve with NIS and log-likelihood, and chi-square quantiles.
#pragma once

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>
#include <numbers>
#include <type_traits>
#include <utility>

#include "ctxfuse/core/types.hpp"

namespace ctxfuse {

namespace detail {
template <std::size_t... I, class F>
constexpr void static_for_impl(std::index_sequence<I...>, F&& f) {
  (f(std::integral_constant<std::size_t, I>{}), ...);
}
/// f(integral_constant<0>), ..., f(integral_constant<Count - 1>): compile-time offsets and
/// sizes in the loop body, so every block expression below has fixed dimensions.
template <std::size_t Count, class F>
constexpr void static_for(F&& f) {
  static_for_impl(std::make_index_sequence<Count>{}, std::forward<F>(f));
}

}  // namespace detail

/// True when no element is NaN or Inf. x * 0 is 0 for finite x and NaN otherwise, so one
/// vectorised multiply-add pass decides; Eigen's allFinite() is not vectorised.
template <class Derived>
bool all_finite(const Eigen::DenseBase<Derived>& m) {
  return (m.derived().array() * typename Derived::Scalar(0)).sum() == typename Derived::Scalar(0);
}

namespace detail {
/// Column J of the strict upper triangle from row J of the lower one, for J = 1 .. N-1, as
/// straight-line code (compile-time indices, no loop).
template <int N, int J = 1>
inline void mirror_lower_columns(double* d) {
  if constexpr (J < N) {
    [&]<int... I>(std::integer_sequence<int, I...>) { ((d[I + J * N] = d[J + I * N]), ...); }(
        std::make_integer_sequence<int, J>{});
    mirror_lower_columns<N, J + 1>(d);
  }
}
}  // namespace detail

/// Makes P exactly symmetric by mirroring its lower triangle onto the upper one. The two
/// triangles of a covariance computed by the filters differ only by rounding, so averaging
/// them would buy nothing and cost three times as much (strided reads of both triangles).
///
/// Fixed-size, column-major, contiguous double matrices (every covariance of the filters) take
/// straight-line copies: about 200 instructions for a 15x15 against about 770 for Eigen's
/// triangular-view assignment, which is a loop with a test per element (16 mirrors per
/// three-mode IMM step). Everything else takes the triangular view.
///
/// Why not a plain loop: g++ 12.2 (-O1 and -O2, no -march flag) miscompiled
/// `for j, for i < j: P(i, j) = P(j, i)` in one inlining context. In `ekf::update` the local
/// posterior, whose lower triangle had just been written, was copied out with its upper
/// triangle uninitialised (valgrind), and the UWB-alone tracker of the region pipeline drifted
/// by kilometres, in the demo binary only (the test binaries inline differently). The fault
/// goes away with -fno-tree-fre and with an empty asm statement that clobbers memory after
/// the loop: g++'s value numbering forwarded the matrix's contents from before the loop's
/// stores to the copy. The straight-line form gives the right result in that same binary; the
/// asm statement below (no instruction) keeps value numbering from looking past the stores
/// in any case. CI's scripts/compare_compilers.sh runs the demo from g++ and clang builds and
/// requires identical numbers, which is what caught the fault.
template <class Derived>
void symmetrize(Eigen::MatrixBase<Derived>& P) {
  constexpr int n = Derived::RowsAtCompileTime;
  if constexpr (n != Eigen::Dynamic && n == Derived::ColsAtCompileTime && n <= 32 &&
                std::is_same_v<typename Derived::Scalar, double> && !(Derived::Flags & Eigen::RowMajorBit) &&
                Derived::InnerStrideAtCompileTime == 1 && Derived::OuterStrideAtCompileTime == n) {
    double* d = P.derived().data();
    detail::mirror_lower_columns<n>(d);
    asm volatile("" : : "r"(d) : "memory");
  } else {
    P.template triangularView<Eigen::StrictlyUpper>() = P.transpose();
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

/// out = P - A B' on the lower triangle (diagonal included); the strict upper triangle of
/// `out` is left as it was. A and B are N x K with small K. One fixed-length column segment
/// per column, unrolled, the K terms summed in registers: fewer instructions than a runtime
/// loop over rows or Eigen's coefficient-based product of the same shape (whose default
/// product path, blocked GEMM, costs more still).
template <int N, int K>
void lower_minus_product(const SquareMatrix<N>& P, const Matrix<N, K>& A, const Matrix<N, K>& B,
                         SquareMatrix<N>& out) {
  detail::static_for<N>([&](auto jc) {
    constexpr int j = static_cast<int>(decltype(jc)::value);
    constexpr int len = N - j;
    Vector<len> acc = P.col(j).template segment<len>(j);
    for (int k = 0; k < K; ++k) acc -= B(j, k) * A.col(k).template segment<len>(j);
    out.col(j).template segment<len>(j) = acc;
  });
}

/// out += Q on the lower triangle.
template <int N>
void add_lower(SquareMatrix<N>& out, const SquareMatrix<N>& Q) {
  // Fixed-length column segments, unrolled.
  detail::static_for<N>([&](auto jc) {
    constexpr int j = static_cast<int>(decltype(jc)::value);
    out.col(j).template segment<N - j>(j) += Q.col(j).template segment<N - j>(j);
  });
}

/// The Joseph form expanded: with S = H P H' + R and PHt = P H',
///   (I - K H) P (I - K H)' + K R K' = P - K PHt' - PHt K' + K S K'
/// holds exactly for ANY gain K, so this keeps the Joseph form's first-order insensitivity to
/// gain errors while costing O(N^2 M) instead of the O(N^3) of multiplying out (I - K H).
/// (What it does not keep is the congruence structure, which guarantees semi-definiteness
/// under rounding; joseph_update above keeps it, at N^3.)
/// Computed as one rank-2M product, P - [K, U] [PHt, -K]' with U = K S - PHt (expand it: the
/// same four terms), in one pass over the LOWER triangle of `out` only: the strict upper
/// triangle is left unspecified (callers mirror it once, after any reset, with symmetrize).
template <int N, int M>
void joseph_update_expanded_lower(const SquareMatrix<N>& P, const Matrix<N, M>& K, const Matrix<N, M>& PHt,
                                  const SquareMatrix<M>& S, SquareMatrix<N>& out) {
  Matrix<N, 2 * M> left, right;
  left.template leftCols<M>() = K;
  left.template rightCols<M>().noalias() = K.lazyProduct(S);
  left.template rightCols<M>() -= PHt;
  right.template leftCols<M>() = PHt;
  right.template rightCols<M>() = -K;
  lower_minus_product<N, 2 * M>(P, left, right, out);
}

/// The same, as a full symmetric matrix.
template <int N, int M>
SquareMatrix<N> joseph_update_expanded(const SquareMatrix<N>& P, const Matrix<N, M>& K, const Matrix<N, M>& PHt,
                                       const SquareMatrix<M>& S) {
  SquareMatrix<N> out;
  joseph_update_expanded_lower<N, M>(P, K, PHt, S, out);
  symmetrize(out);
  return out;
}

/// Lower Cholesky factor L (A = L L') of a small fixed-size matrix, from A's lower triangle.
/// Plain loops over compile-time bounds, which the compiler unrolls: Eigen's LLT runs its
/// dynamic-size blocked kernel even for a 3x3. False when a pivot is not positive and finite
/// (NaN anywhere in the lower triangle reaches a pivot); L is then unspecified.
template <int M>
bool cholesky_lower(const SquareMatrix<M>& A, SquareMatrix<M>& L) {
  for (int j = 0; j < M; ++j) {
    double d = A(j, j);
    for (int k = 0; k < j; ++k) d -= L(j, k) * L(j, k);
    // NaN fails the comparison; +Inf fails the finiteness test.
    if (!(d > 0.0) || !(d < std::numeric_limits<double>::infinity())) return false;
    const double ljj = std::sqrt(d);
    const double inv = 1.0 / ljj;
    L(j, j) = ljj;
    for (int i = j + 1; i < M; ++i) {
      double s = A(i, j);
      for (int k = 0; k < j; ++k) s -= L(i, k) * L(j, k);
      L(i, j) = s * inv;
    }
    for (int i = 0; i < j; ++i) L(i, j) = 0.0;
  }
  return true;
}

/// Cholesky factorisation of an innovation covariance S with what the update needs from it.
template <int M>
struct InnovationSolve {
  SquareMatrix<M> L;  // S = L L', lower triangular
  bool ok = false;

  explicit InnovationSolve(const SquareMatrix<M>& S) { ok = cholesky_lower<M>(S, L); }

  /// L^-1 y (forward substitution): its squared norm is the NIS.
  Vector<M> whiten(const Vector<M>& y) const {
    Vector<M> w;
    for (int i = 0; i < M; ++i) {
      double s = y(i);
      for (int k = 0; k < i; ++k) s -= L(i, k) * w(k);
      w(i) = s / L(i, i);
    }
    return w;
  }
  /// y' S^-1 y
  double nis(const Vector<M>& y) const { return whiten(y).squaredNorm(); }
  double log_det() const {
    // One logarithm of the product of the pivots; the sum of logs only when the product
    // leaves the double range (it cannot for innovation covariances of sane units).
    const auto d = L.diagonal();
    const double prod = d.prod();
    if (prod > 1e-150 && prod < 1e150) return 2.0 * std::log(prod);
    return 2.0 * d.array().log().sum();
  }
  /// log N(y; 0, S)
  double log_likelihood(double nis_value) const {
    return -0.5 * (nis_value + log_det() + M * std::log(2.0 * std::numbers::pi));
  }
  /// K = B S^-1 (e.g. the gain P H' S^-1) by two triangular solves on the columns of B:
  /// W L' = B forwards, then K L = W backwards. Each step is a length-N axpy, no inverse.
  template <int N>
  Matrix<N, M> right_solve(const Matrix<N, M>& B) const {
    Matrix<N, M> K;
    for (int c = 0; c < M; ++c) {
      K.col(c) = B.col(c);
      for (int k = 0; k < c; ++k) K.col(c) -= L(c, k) * K.col(k);
      K.col(c) *= 1.0 / L(c, c);
    }
    for (int c = M - 1; c >= 0; --c) {
      for (int k = c + 1; k < M; ++k) K.col(c) -= L(k, c) * K.col(k);
      K.col(c) *= 1.0 / L(c, c);
    }
    return K;
  }
};

/// Positive definiteness through a Cholesky attempt (the cheapest complete test).
template <class Derived>
bool is_positive_definite(const Eigen::MatrixBase<Derived>& A) {
  constexpr int rows = Derived::RowsAtCompileTime;
  if constexpr (std::is_same_v<typename Derived::Scalar, double> && rows != Eigen::Dynamic &&
                rows == Derived::ColsAtCompileTime && rows <= 6) {
    SquareMatrix<rows> L;
    return cholesky_lower<rows>(A, L);
  } else {
    using Mat = Eigen::Matrix<typename Derived::Scalar, Derived::RowsAtCompileTime, Derived::ColsAtCompileTime>;
    Eigen::LLT<Mat> llt(A.derived());
    if (llt.info() != Eigen::Success) return false;
    const auto d = llt.matrixLLT().diagonal();
    return d.allFinite() && (d.array() > 0.0).all();
  }
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

namespace detail {
/// Where a matrix stops being row-stochastic, row by row: the first entry negative or not
/// finite (`col` >= 0), or the first row whose sum is off 1 by more than `tol` (`col` = -1,
/// `sum` its sum); `row` = -1 when every entry is finite and >= 0 and every row sums to 1.
/// The one test behind the IMM's per-cycle check and the mixing policies' settings checks.
struct StochasticFault {
  int row = -1;
  int col = -1;
  double sum = 0.0;
};

template <int R>
StochasticFault first_stochastic_fault(const SquareMatrix<R>& P, double tol = 1e-9) {
  for (int i = 0; i < R; ++i) {
    double s = 0.0;
    for (int j = 0; j < R; ++j) {
      if (!std::isfinite(P(i, j)) || P(i, j) < 0.0) return {i, j, s};
      s += P(i, j);
    }
    if (std::abs(s - 1.0) > tol) return {i, -1, s};
  }
  return {};
}
}  // namespace detail

}  // namespace ctxfuse

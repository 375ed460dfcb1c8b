// Normal equations of a chain of states: the Gauss-Newton system of a sliding window whose
// factors touch one state (priors, measurements) or two consecutive states (motion) is block
// tridiagonal. Stored as fixed-size dense blocks and solved by block Cholesky (the block
// Thomas algorithm) in O(K N^3), with no sparse-matrix machinery and no heap: the whole
// structure is known at compile time.
//
// The last Schur complement of the forward sweep is the marginal information of the last
// state, so its covariance comes for free, which is what users of fixed-lag smoothers ask for.
// Marginalising the first state into a prior on the second is the same Schur complement,
// taken the other way round (marginalize_first below).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "ctxfuse/core/factor.hpp"
#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/status.hpp"

namespace ctxfuse {

/// H = sum J' J and g = sum J' r over the factors added, for up to K states of dimension N,
/// and the cost 1/2 sum |r|^2. diagonal[i] = H(i, i), upper[i] = H(i, i + 1).
template <int N, int K>
struct BlockTridiagonal {
  static_assert(K >= 1);
  int size = 0;
  double cost = 0.0;
  std::array<SquareMatrix<N>, K> diagonal{};
  std::array<SquareMatrix<N>, K> upper{};
  std::array<Vector<N>, K> gradient{};

  void reset(int n) {
    size = n;
    cost = 0.0;
    for (int i = 0; i < n; ++i) {
      diagonal[static_cast<std::size_t>(i)].setZero();
      upper[static_cast<std::size_t>(i)].setZero();
      gradient[static_cast<std::size_t>(i)].setZero();
    }
  }

  /// Adds a factor on state i; false (and nothing added) when its residual or Jacobian is not finite.
  template <UnaryFactor F>
  bool add(const F& f, int i, const Vector<N>& x) {
    Matrix<F::dim, N> J;
    const Vector<F::dim> r = f.evaluate(x, &J);
    if (!all_finite(r) || !all_finite(J)) return false;
    const auto k = static_cast<std::size_t>(i);
    diagonal[k].noalias() += J.transpose().lazyProduct(J);
    gradient[k].noalias() += J.transpose().lazyProduct(r);
    cost += 0.5 * r.squaredNorm();
    return true;
  }

  /// Adds a factor on states i and i + 1.
  template <BinaryFactor F>
  bool add(const F& f, int i, const Vector<N>& xi, const Vector<N>& xj) {
    Matrix<F::dim, N> Ji, Jj;
    const Vector<F::dim> r = f.evaluate(xi, xj, &Ji, &Jj);
    if (!all_finite(r) || !all_finite(Ji) || !all_finite(Jj)) return false;
    const auto k = static_cast<std::size_t>(i);
    diagonal[k].noalias() += Ji.transpose().lazyProduct(Ji);
    diagonal[k + 1].noalias() += Jj.transpose().lazyProduct(Jj);
    upper[k].noalias() += Ji.transpose().lazyProduct(Jj);
    gradient[k].noalias() += Ji.transpose().lazyProduct(r);
    gradient[k + 1].noalias() += Jj.transpose().lazyProduct(r);
    cost += 0.5 * r.squaredNorm();
    return true;
  }
};

/// Inverse of a small symmetric positive definite matrix from its LDL' factorisation (unit
/// lower L, D > 0): S^-1 = L^-T D^-1 L^-1, reading S's lower triangle. No square roots, and
/// every loop bound a compile-time constant (static_for over the columns), so the compiler
/// emits straight-line code: the smoother inverts one block per state per iteration, and
/// with cholesky_lower's run-time loops and square roots that took a fifth of a step.
/// False when a pivot is not positive and finite (S not positive definite, or NaN/Inf).
template <int N>
bool spd_inverse(const SquareMatrix<N>& S, SquareMatrix<N>& S_inv) {
  SquareMatrix<N> L = SquareMatrix<N>::Identity();
  Vector<N> d, inv_d;
  bool ok = true;
  detail::static_for<N>([&](auto jc) {
    constexpr int j = static_cast<int>(decltype(jc)::value);
    double dj = S(j, j);
    for (int k = 0; k < j; ++k) dj -= L(j, k) * L(j, k) * d(k);
    // NaN fails the comparison; +Inf fails the finiteness test.
    ok = ok && dj > 0.0 && dj < std::numeric_limits<double>::infinity();
    d(j) = dj;
    inv_d(j) = 1.0 / dj;
    for (int i = j + 1; i < N; ++i) {
      double acc = S(i, j);
      for (int k = 0; k < j; ++k) acc -= L(i, k) * L(j, k) * d(k);
      L(i, j) = acc * inv_d(j);
    }
  });
  if (!ok) return false;
  SquareMatrix<N> Li = SquareMatrix<N>::Identity();  // L^-1, unit lower triangular
  detail::static_for<N>([&](auto jc) {
    constexpr int j = static_cast<int>(decltype(jc)::value);
    for (int i = j + 1; i < N; ++i) {
      double acc = L(i, j);
      for (int k = j + 1; k < i; ++k) acc += L(i, k) * Li(k, j);
      Li(i, j) = -acc;
    }
  });
  const SquareMatrix<N> DLi = inv_d.asDiagonal() * Li;
  S_inv.noalias() = Li.transpose().lazyProduct(DLi);
  symmetrize(S_inv);
  return all_finite(S_inv);
}

/// Block Cholesky (block Thomas) of a BlockTridiagonal, optionally damped (Levenberg-
/// Marquardt): each diagonal block gets lambda * max(diag, 1e-6) added on its diagonal,
/// Ceres' scaling, so the damping does not depend on the units of the state.
///   S_0 = D_0,  S_i = D_i - U_{i-1}' S_{i-1}^-1 U_{i-1},  G_i = S_i^-1 U_i
/// The S_i^-1 are kept explicitly: N is small, and every later use is then a fixed-size
/// matrix product instead of a triangular solve; the last one is the marginal covariance.
template <int N, int K>
struct BlockTridiagonalCholesky {
  int size = 0;
  std::array<SquareMatrix<N>, K> S_inv{};
  std::array<SquareMatrix<N>, K> G{};

  /// Problem::system_not_positive_definite when a Schur complement is not (rank deficiency,
  /// NaN, an indefinite factor); the factorisation is then unusable.
  Problem factorize(const BlockTridiagonal<N, K>& sys, double lambda = 0.0) {
    size = sys.size;
    for (int i = 0; i < size; ++i) {
      const auto k = static_cast<std::size_t>(i);
      SquareMatrix<N> S = sys.diagonal[k];
      if (lambda > 0.0)
        for (int j = 0; j < N; ++j) S(j, j) += lambda * std::max(sys.diagonal[k](j, j), 1e-6);
      if (i > 0) S.noalias() -= sys.upper[k - 1].transpose().lazyProduct(G[k - 1]);
      if (!spd_inverse<N>(S, S_inv[k])) return Problem::system_not_positive_definite;
      if (i + 1 < size) G[k].noalias() = S_inv[k].lazyProduct(sys.upper[k]);
    }
    return Problem::none;
  }

  /// x = H^-1 b (H the factorised matrix).
  void solve(const std::array<Vector<N>, K>& b, std::array<Vector<N>, K>& x) const {
    // Forward: c_i = b_i - U_{i-1}' S_{i-1}^-1 c_{i-1} = b_i - G_{i-1}' c_{i-1} (S symmetric),
    // e_i = S_i^-1 c_i, held in x. Backward: x_i = e_i - G_i x_{i+1}.
    Vector<N> c = b[0];
    for (int i = 0; i < size; ++i) {
      const auto k = static_cast<std::size_t>(i);
      if constexpr (K > 1) {  // (K = 1: g++ cannot see that the index stays in bounds)
        if (i > 0) {
          Vector<N> next = b[k];
          next.noalias() -= G[k - 1].transpose().lazyProduct(c);
          c = next;
        }
      }
      x[k].noalias() = S_inv[k].lazyProduct(c);
    }
    if constexpr (K > 1) {
      for (int i = size - 2; i >= 0; --i) {
        const auto k = static_cast<std::size_t>(i);
        x[k].noalias() -= G[k].lazyProduct(x[k + 1]);
      }
    }
  }

  /// S_{n-1}^-1: the marginal covariance of the last state under the factorised information.
  const SquareMatrix<N>& last_covariance() const { return S_inv[static_cast<std::size_t>(size - 1)]; }
};

/// Marginalises state 0 of a two-state system made of ONLY the factors that touch state 0
/// (its prior, its measurements, the motion factor to state 1), linearised at (x0, x1):
///   Lambda = H11 - H10 H00^-1 H01,   eta = g1 - H10 H00^-1 g0,   mean = x1 - Lambda^-1 eta
/// is the Gaussian prior on state 1 that those factors leave behind (their quadratic model
/// minimised over state 0). Fails with a Status, leaving `out` as it was, when H00 or Lambda
/// is not positive definite.
template <int N>
Status marginalize_first(const BlockTridiagonal<N, 2>& sys, const Vector<N>& x1, PriorFactor<N>& out) {
  if (sys.size != 2) return Status::invalid(Problem::too_few_measurements);
  SquareMatrix<N> H00_inv;
  if (!spd_inverse<N>(sys.diagonal[0], H00_inv)) return Status::failure(Problem::system_not_positive_definite);
  // T = H00^-1 H01: H10 H00^-1 H01 = H01' T, H10 H00^-1 g0 = T' g0.
  const SquareMatrix<N> T = H00_inv.lazyProduct(sys.upper[0]);
  SquareMatrix<N> Lambda = sys.diagonal[1];
  Lambda.noalias() -= sys.upper[0].transpose().lazyProduct(T);
  symmetrize(Lambda);
  Vector<N> eta = sys.gradient[1];
  eta.noalias() -= T.transpose() * sys.gradient[0];
  PriorFactor<N> prior;
  SquareMatrix<N> L1, Lambda_inv;
  if (!all_finite(Lambda) || !cholesky_lower<N>(Lambda, L1) || !spd_inverse<N>(Lambda, Lambda_inv))
    return Status::failure(Problem::system_not_positive_definite);
  const Vector<N> step = Lambda_inv * eta;
  prior.mean = x1 - step;
  prior.W = L1.transpose();
  if (!all_finite(prior.mean) || !all_finite(prior.W)) return Status::failure(Problem::system_not_positive_definite);
  out = prior;
  return Status{};
}

}  // namespace ctxfuse

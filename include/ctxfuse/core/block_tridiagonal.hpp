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
    diagonal[k].noalias() += J.transpose() * J;
    gradient[k].noalias() += J.transpose() * r;
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
    diagonal[k].noalias() += Ji.transpose() * Ji;
    diagonal[k + 1].noalias() += Jj.transpose() * Jj;
    upper[k].noalias() += Ji.transpose() * Jj;
    gradient[k].noalias() += Ji.transpose() * r;
    gradient[k + 1].noalias() += Jj.transpose() * r;
    cost += 0.5 * r.squaredNorm();
    return true;
  }
};

/// Block Cholesky of a BlockTridiagonal, optionally damped (Levenberg-Marquardt): each
/// diagonal block gets lambda * max(diag, 1e-6) added on its diagonal, Ceres' scaling, so
/// the damping does not depend on the units of the state.
///   S_0 = D_0,  S_i = D_i - U_{i-1}' S_{i-1}^-1 U_{i-1},  G_i = S_i^-1 U_i
template <int N, int K>
struct BlockTridiagonalCholesky {
  int size = 0;
  std::array<SquareMatrix<N>, K> L{};  // S_i = L_i L_i'
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
      if (i > 0) S.noalias() -= sys.upper[k - 1].transpose() * G[k - 1];
      if (!cholesky_lower<N>(S, L[k])) return Problem::system_not_positive_definite;
      if (i + 1 < size) {
        G[k] = sys.upper[k];
        solve_block(k, G[k]);
      }
    }
    return Problem::none;
  }

  /// x = H^-1 b (H the factorised matrix).
  void solve(const std::array<Vector<N>, K>& b, std::array<Vector<N>, K>& x) const {
    // Forward: c_i = b_i - U_{i-1}' S_{i-1}^-1 c_{i-1} = b_i - G_{i-1}' c_{i-1} (S symmetric),
    // e_i = S_i^-1 c_i, held in x.
    std::array<Vector<N>, K> c{};
    for (int i = 0; i < size; ++i) {
      const auto k = static_cast<std::size_t>(i);
      c[k] = b[k];
      if (i > 0) c[k].noalias() -= G[k - 1].transpose() * c[k - 1];
      x[k] = c[k];
      solve_block(k, x[k]);
    }
    // Backward: x_i = e_i - G_i x_{i+1}.
    for (int i = size - 2; i >= 0; --i) {
      const auto k = static_cast<std::size_t>(i);
      x[k].noalias() -= G[k] * x[k + 1];
    }
  }

  /// S_{n-1}^-1: the marginal covariance of the last state under the factorised information.
  SquareMatrix<N> last_covariance() const {
    SquareMatrix<N> P = SquareMatrix<N>::Identity();
    solve_block(static_cast<std::size_t>(size - 1), P);
    symmetrize(P);
    return P;
  }

 private:
  template <class Derived>
  void solve_block(std::size_t k, Eigen::MatrixBase<Derived>& B) const {
    L[k].template triangularView<Eigen::Lower>().solveInPlace(B);
    L[k].template triangularView<Eigen::Lower>().transpose().solveInPlace(B);
  }
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
  SquareMatrix<N> L0;
  if (!cholesky_lower<N>(sys.diagonal[0], L0)) return Status::failure(Problem::system_not_positive_definite);
  // A = L0^-1 H01, a = L0^-1 g0: H10 H00^-1 H01 = A' A, H10 H00^-1 g0 = A' a.
  SquareMatrix<N> A = sys.upper[0];
  Vector<N> a = sys.gradient[0];
  L0.template triangularView<Eigen::Lower>().solveInPlace(A);
  L0.template triangularView<Eigen::Lower>().solveInPlace(a);
  SquareMatrix<N> Lambda = sys.diagonal[1];
  Lambda.noalias() -= A.transpose() * A;
  symmetrize(Lambda);
  Vector<N> eta = sys.gradient[1];
  eta.noalias() -= A.transpose() * a;
  PriorFactor<N> prior;
  SquareMatrix<N> L1;
  if (!all_finite(Lambda) || !cholesky_lower<N>(Lambda, L1))
    return Status::failure(Problem::system_not_positive_definite);
  Vector<N> step = eta;
  L1.template triangularView<Eigen::Lower>().solveInPlace(step);
  L1.template triangularView<Eigen::Lower>().transpose().solveInPlace(step);
  prior.mean = x1 - step;
  prior.W = L1.transpose();
  if (!all_finite(prior.mean) || !all_finite(prior.W)) return Status::failure(Problem::system_not_positive_definite);
  out = prior;
  return Status{};
}

}  // namespace ctxfuse

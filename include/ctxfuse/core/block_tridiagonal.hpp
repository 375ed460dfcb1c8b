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

#include "ctxfuse/core/block_sparsity.hpp"
#include "ctxfuse/core/factor.hpp"
#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/status.hpp"

namespace ctxfuse {

/// The normal-equation blocks of a binary factor r = W d, d = xj - A xi - b, whose Jacobians
/// -W A and W do not depend on the states (the motion factor of an affine process model):
///   Hii = A' W'W A,  Hji = -W'W A,  Hjj = W'W,
/// formed once when the factor is made. At each linearisation its J'r is then Hji' d and
/// Hjj d, and its cost d' Hjj d / 2, from d alone (`f.unwhitened(xi, xj)`): two 4 x 4
/// products instead of the Jacobians and five products, and three blocks to keep per factor.
template <int N>
struct AffineFactorBlocks {
  SquareMatrix<N> Hii = SquareMatrix<N>::Zero(), Hji = SquareMatrix<N>::Zero(), Hjj = SquareMatrix<N>::Zero();

  /// From the factor's Jacobians at (xi, xj) (any point, for such a factor); false, nothing
  /// changed, when they are not finite.
  template <BinaryFactor F>
  bool compute(const F& f, const Vector<N>& xi, const Vector<N>& xj) {
    static_assert(F::dim == N);
    SquareMatrix<N> Ji, Jj;
    (void)f.evaluate(xi, xj, &Ji, &Jj);
    if (!all_finite(Ji) || !all_finite(Jj)) return false;
    Hii.noalias() = Ji.transpose().lazyProduct(Ji);
    Hji.noalias() = Jj.transpose().lazyProduct(Ji);
    Hjj.noalias() = Jj.transpose().lazyProduct(Jj);
    return true;
  }
};

/// The information Lambda = W'W of a binary factor r = W d, d = xj - f(xi), whose Jacobians
/// are -W F(xi) and W (a motion factor whose model subtracts plainly but is not affine):
///   Hii = F' Lambda F,  Hji = -Lambda F,  Hjj = Lambda,  J'r = -F' Lambda d and Lambda d,
/// so Hjj is a constant of the factor and a linearisation costs two N x N products (Lambda F,
/// then F' times it) instead of forming W F and three J'J products. Formed once when the
/// factor is made (`f.W`); the factor supplies d and F (`f.unwhitened(xi, xj, &F)`).
template <int N>
struct WhitenedInformation {
  SquareMatrix<N> Lambda = SquareMatrix<N>::Zero();

  /// False, nothing changed, when W is not finite.
  template <BinaryFactor F>
  bool compute(const F& f) {
    static_assert(F::dim == N);
    if (!all_finite(f.W)) return false;
    Lambda.noalias() = f.W.transpose().lazyProduct(f.W);
    return true;
  }
};

/// H = sum J' J and g = sum J' r over the factors added, for up to K states of dimension N,
/// and the cost 1/2 sum |r|^2. diagonal[i] = H(i, i), lower[i] = H(i + 1, i) (the block
/// below the diagonal, so that every product of the solve below is a plain one: a
/// transposed left operand makes Eigen form dot products, whose scalar results stall on
/// store forwarding when read back as vectors).
template <int N, int K>
struct BlockTridiagonal {
  static_assert(K >= 1);
  int size = 0;
  double cost = 0.0;
  std::array<SquareMatrix<N>, K> diagonal{};
  std::array<SquareMatrix<N>, K> lower{};
  std::array<Vector<N>, K> gradient{};

  void reset(int n) {
    size = n;
    cost = 0.0;
    for (int i = 0; i < n; ++i) {
      diagonal[static_cast<std::size_t>(i)].setZero();
      lower[static_cast<std::size_t>(i)].setZero();
      gradient[static_cast<std::size_t>(i)].setZero();
    }
  }

  /// Adds a factor on state i; false (and nothing added) when its residual or Jacobian is not
  /// finite. A measurement factor whose model declares `jacobian_columns` (a range touches
  /// the position block only) adds only those blocks of J'J and J'r.
  template <UnaryFactor F>
  bool add(const F& f, int i, const Vector<N>& x) {
    Matrix<F::dim, N> J;
    const Vector<F::dim> r = f.evaluate(x, &J);
    if (!all_finite(r) || !all_finite(J)) return false;
    const auto k = static_cast<std::size_t>(i);
    if constexpr (requires { F::Model::jacobian_columns; }) {
      constexpr auto pat = F::Model::jacobian_columns;
      using L = typename decltype(pat)::layout;
      static_assert(L::size == N, "jacobian_columns over another layout");
      detail::static_for<decltype(pat)::size>([&](auto ka) {
        constexpr std::size_t a = static_cast<std::size_t>(pat.block[ka]);
        constexpr int oa = L::offsets[a], sa = L::sizes[a];
        detail::static_for<decltype(pat)::size>([&](auto kb) {
          constexpr std::size_t b = static_cast<std::size_t>(pat.block[kb]);
          constexpr int ob = L::offsets[b], sb = L::sizes[b];
          diagonal[k].template block<sa, sb>(oa, ob).noalias() +=
              J.template middleCols<sa>(oa).transpose().lazyProduct(J.template middleCols<sb>(ob));
        });
        gradient[k].template segment<sa>(oa).noalias() += J.template middleCols<sa>(oa).transpose().lazyProduct(r);
      });
    } else {
      diagonal[k].noalias() += J.transpose().lazyProduct(J);
      gradient[k].noalias() += J.transpose().lazyProduct(r);
    }
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
    lower[k].noalias() += Jj.transpose().lazyProduct(Ji);
    gradient[k].noalias() += Ji.transpose().lazyProduct(r);
    gradient[k + 1].noalias() += Jj.transpose().lazyProduct(r);
    cost += 0.5 * r.squaredNorm();
    return true;
  }

  /// Adds a binary factor r = W (xj - f(xi)) on states i and i + 1 from its information
  /// (WhitenedInformation).
  template <BinaryFactor F>
  bool add(const F& f, const WhitenedInformation<N>& info, int i, const Vector<N>& xi, const Vector<N>& xj) {
    SquareMatrix<N> Fx;
    const Vector<N> d = f.unwhitened(xi, xj, &Fx);
    if (!all_finite(d) || !all_finite(Fx)) return false;
    const auto k = static_cast<std::size_t>(i);
    const SquareMatrix<N> LF = info.Lambda.lazyProduct(Fx);
    const SquareMatrix<N> FtL = LF.transpose();  // F' Lambda, stored: plain products below
    const Vector<N> gj = info.Lambda.lazyProduct(d);
    diagonal[k].noalias() += FtL.lazyProduct(Fx);
    diagonal[k + 1] += info.Lambda;
    lower[k] -= LF;
    gradient[k].noalias() -= FtL.lazyProduct(d);
    gradient[k + 1] += gj;
    cost += 0.5 * d.dot(gj);
    return true;
  }

  /// Adds an affine binary factor on states i and i + 1 from its blocks (AffineFactorBlocks).
  template <BinaryFactor F>
  bool add(const F& f, const AffineFactorBlocks<N>& blocks, int i, const Vector<N>& xi, const Vector<N>& xj) {
    const Vector<N> d = f.unwhitened(xi, xj);
    if (!all_finite(d)) return false;
    const auto k = static_cast<std::size_t>(i);
    diagonal[k] += blocks.Hii;
    diagonal[k + 1] += blocks.Hjj;
    lower[k] += blocks.Hji;
    const Vector<N> gj = blocks.Hjj.lazyProduct(d);
    gradient[k].noalias() += blocks.Hji.transpose().lazyProduct(d);
    gradient[k + 1] += gj;
    cost += 0.5 * d.dot(gj);
    return true;
  }
};

namespace detail {
/// The 4 x 4 case of spd_inverse by 2 x 2 blocks, S = [A B; B' C]:
///   S^-1 = [A^-1 + T Z T', -T Z; -Z T', Z],  T = A^-1 B,  Z = (C - B' T)^-1,
/// each 2 x 2 inverse in closed form. A symmetric 2 x 2 is positive definite exactly when
/// its (0, 0) entry and its determinant are positive, so the two pivots (A, then the Schur
/// complement) decide S's definiteness as the LDL' pivots do. Two divisions instead of four
/// in a dependent chain, everything in registers: 4 x 4 is the planar position-velocity
/// state of the UWB smoother, whose block Cholesky inverts one such block per state and
/// iteration. Every entry of S's lower triangle reaches a pivot, so NaN fails a comparison
/// there; the outputs are tested in registers (x * 0 is 0 only for finite x), because
/// reading a just-stored matrix back as vectors stalls on store forwarding.
inline bool spd_inverse_4x4(const SquareMatrix<4>& S, SquareMatrix<4>& S_inv) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  const double a00 = S(0, 0), a10 = S(1, 0), a11 = S(1, 1);
  const double det_a = a00 * a11 - a10 * a10;
  if (!(a00 > 0.0 && det_a > 0.0 && det_a < inf)) return false;
  const double inv_det_a = 1.0 / det_a;
  const double ai00 = a11 * inv_det_a, ai10 = -a10 * inv_det_a, ai11 = a00 * inv_det_a;
  const double b00 = S(2, 0), b01 = S(3, 0), b10 = S(2, 1), b11 = S(3, 1);  // B = S(0:2, 2:4)
  const double t00 = ai00 * b00 + ai10 * b10, t01 = ai00 * b01 + ai10 * b11;
  const double t10 = ai10 * b00 + ai11 * b10, t11 = ai10 * b01 + ai11 * b11;
  const double c00 = S(2, 2) - (b00 * t00 + b10 * t10);
  const double c10 = S(3, 2) - (b01 * t00 + b11 * t10);
  const double c11 = S(3, 3) - (b01 * t01 + b11 * t11);
  const double det_c = c00 * c11 - c10 * c10;
  if (!(c00 > 0.0 && det_c > 0.0 && det_c < inf)) return false;
  const double inv_det_c = 1.0 / det_c;
  const double z00 = c11 * inv_det_c, z10 = -c10 * inv_det_c, z11 = c00 * inv_det_c;
  const double m00 = t00 * z00 + t01 * z10, m01 = t00 * z10 + t01 * z11;  // M = T Z
  const double m10 = t10 * z00 + t11 * z10, m11 = t10 * z10 + t11 * z11;
  const double u00 = ai00 + (m00 * t00 + m01 * t01);
  const double u10 = ai10 + (m10 * t00 + m11 * t01);
  const double u11 = ai11 + (m10 * t10 + m11 * t11);
  const double zero = ((u00 * 0.0 + u10 * 0.0) + (u11 * 0.0 + m00 * 0.0)) +
                      ((m01 * 0.0 + m10 * 0.0) + (m11 * 0.0 + z00 * 0.0)) + (z10 * 0.0 + z11 * 0.0);
  if (zero != 0.0) return false;
  double* o = S_inv.data();  // column-major
  o[0] = u00, o[1] = u10, o[2] = -m00, o[3] = -m01;
  o[4] = u10, o[5] = u11, o[6] = -m10, o[7] = -m11;
  o[8] = -m00, o[9] = -m10, o[10] = z00, o[11] = z10;
  o[12] = -m01, o[13] = -m11, o[14] = z10, o[15] = z11;
  return true;
}

/// The 8 x 8 case by 4 x 4 blocks, S = [A B; B' C] (B' read from S's lower triangle), with the
/// same algebra as the 4 x 4 one: T = A^-1 B, Z = (C - B' T)^-1, M = T Z,
///   S^-1 = [A^-1 + M T', -M; -M', Z].
/// S is positive definite exactly when A and its Schur complement are, which the two 4 x 4
/// inversions decide. Four 4 x 4 products instead of the 8 x 8 LDL' and its triangular
/// inverse: the planar IMU state of the UWB/IMU smoother inverts one such block per state and
/// iteration.
inline bool spd_inverse_8x8(const SquareMatrix<8>& S, SquareMatrix<8>& S_inv) {
  SquareMatrix<4> A_inv, Z;
  if (!spd_inverse_4x4(S.topLeftCorner<4, 4>(), A_inv)) return false;
  const SquareMatrix<4> Bt = S.bottomLeftCorner<4, 4>();  // B'
  SquareMatrix<4> T;
  T.noalias() = A_inv.lazyProduct(Bt.transpose());
  SquareMatrix<4> C = S.bottomRightCorner<4, 4>();
  C.noalias() -= Bt.lazyProduct(T);
  if (!spd_inverse_4x4(C, Z)) return false;
  SquareMatrix<4> M;
  M.noalias() = T.lazyProduct(Z);
  S_inv.topLeftCorner<4, 4>() = A_inv;
  S_inv.topLeftCorner<4, 4>().noalias() += M.lazyProduct(T.transpose());
  S_inv.topRightCorner<4, 4>() = -M;
  S_inv.bottomLeftCorner<4, 4>() = -M.transpose();
  S_inv.bottomRightCorner<4, 4>() = Z;
  symmetrize(S_inv);
  return all_finite(S_inv);
}

/// spd_inverse from the LDL' factorisation (unit lower L, D > 0): S^-1 = L^-T D^-1 L^-1. No
/// square roots, and every loop bound a compile-time constant (static_for over the columns),
/// so the compiler emits straight-line code.
template <int N>
bool spd_inverse_ldl(const SquareMatrix<N>& S, SquareMatrix<N>& S_inv) {
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
}  // namespace detail

/// Inverse of a small symmetric positive definite matrix, reading S's lower triangle; false
/// (S_inv unspecified) when S is not positive definite or holds NaN/Inf. The smoother inverts
/// one block per state per iteration: 4 x 4 by 2 x 2 blocks, 8 x 8 by 4 x 4 blocks, other sizes
/// by LDL'.
template <int N>
bool spd_inverse(const SquareMatrix<N>& S, SquareMatrix<N>& S_inv) {
  if constexpr (N == 4)
    return detail::spd_inverse_4x4(S, S_inv);
  else if constexpr (N == 8)
    return detail::spd_inverse_8x8(S, S_inv);
  else
    return detail::spd_inverse_ldl<N>(S, S_inv);
}

/// Block Cholesky (block Thomas) of a BlockTridiagonal, optionally damped (Levenberg-
/// Marquardt): each diagonal block gets lambda * max(diag, 1e-6) added on its diagonal,
/// Ceres' scaling, so the damping does not depend on the units of the state. With
/// L_i = H(i + 1, i) (the system's lower blocks):
///   S_0 = D_0,  S_i = D_i - L_{i-1} G_{i-1},  G_i = S_i^-1 L_i'
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
      if (i > 0) S.noalias() -= sys.lower[k - 1].lazyProduct(G[k - 1]);
      if (!spd_inverse<N>(S, S_inv[k])) return Problem::system_not_positive_definite;
      if (i + 1 < size) G[k].noalias() = S_inv[k].lazyProduct(sys.lower[k].transpose());
    }
    return Problem::none;
  }

  /// x = H^-1 b, H the factorised matrix; `sys` is the system factorised (its lower blocks
  /// enter the forward substitution, read there instead of copied at each factorisation).
  void solve(const BlockTridiagonal<N, K>& sys, const std::array<Vector<N>, K>& b, std::array<Vector<N>, K>& x) const {
    // Forward: c_i = b_i - L_{i-1} S_{i-1}^-1 c_{i-1} = b_i - L_{i-1} e_{i-1},
    // e_i = S_i^-1 c_i, held in x. Backward: x_i = e_i - G_i x_{i+1}.
    for (int i = 0; i < size; ++i) {
      const auto k = static_cast<std::size_t>(i);
      Vector<N> c = b[k];
      if constexpr (K > 1)  // (K = 1: g++ cannot see that the index stays in bounds)
        if (i > 0) c.noalias() -= sys.lower[k - 1].lazyProduct(x[k - 1]);
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
  // T = H00^-1 H01: H10 H00^-1 H01 = H10 T, H10 H00^-1 g0 = T' g0.
  const SquareMatrix<N> T = H00_inv.lazyProduct(sys.lower[0].transpose());
  SquareMatrix<N> Lambda = sys.diagonal[1];
  Lambda.noalias() -= sys.lower[0].lazyProduct(T);
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

// The arithmetic of the IMM (filters/imm.hpp) that needs no mode types: the mixing weights,
// the moment match of weighted Gaussians and the probability floor. Free functions over
// fixed sizes, so the class keeps only the bookkeeping of modes and buffers.
#pragma once

#include <array>
#include <cmath>

#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse::imm::detail {

/// Entries finite and >= 0, every row summing to 1 within `tol`: a matrix mix() accepts.
template <int R>
bool row_stochastic(const SquareMatrix<R>& P, double tol) {
  return ctxfuse::detail::first_stochastic_fault<R>(P, tol).row < 0;
}

/// mu_{i|j} = p_ij mu_i / c_j in column j (Bar-Shalom eq. 11.6.6-7). A mode that no mode can
/// switch into (c_j = 0) keeps its own belief: column j is the unit vector e_j.
template <int R>
void mixing_weights(const SquareMatrix<R>& P, const Vector<R>& mu, const Vector<R>& c, SquareMatrix<R>& w) {
  for (int j = 0; j < R; ++j)
    for (int i = 0; i < R; ++i) w(i, j) = c(j) > 0.0 ? P(i, j) * mu(i) / c(j) : (i == j ? 1.0 : 0.0);
}

/// Lower triangle of sum_i w_i (P_i + d_i d_i') with d_i = dx_i - m, in one pass per column:
/// the weighted covariances and the rank-R spread of the means together, accumulated in
/// registers (the textbook sum, without a pass over the whole matrix per term).
template <int N, int R, class MeanExpr, class WeightExpr>
void moment_match_lower(const std::array<const SquareMatrix<N>*, R>& covs, const Matrix<N, R>& dx, const MeanExpr& m,
                        const WeightExpr& w, SquareMatrix<N>& out) {
  Matrix<N, R> d = dx.colwise() - Vector<N>(m);
  Matrix<N, R> dw = d * Vector<R>(w).asDiagonal();
  double wi[R];
  for (int i = 0; i < R; ++i) wi[i] = w(i);
  for (int c = 0; c < N; ++c) {
    double dc[R];
    const double* pc[R];
    for (int i = 0; i < R; ++i) {
      dc[i] = d(c, i);
      pc[i] = covs[static_cast<std::size_t>(i)]->data() + c * N;
    }
    const double* dwd = dw.data();
    double* o = out.data() + c * N;
    // Two rows at a time, sums in registers (one SIMD pair per step).
    int r = c;
    for (; r + 1 < N; r += 2) {
      double s0 = 0.0, s1 = 0.0;
      for (int i = 0; i < R; ++i) {
        s0 += wi[i] * pc[i][r] + dwd[i * N + r] * dc[i];
        s1 += wi[i] * pc[i][r + 1] + dwd[i * N + r + 1] * dc[i];
      }
      o[r] = s0;
      o[r + 1] = s1;
    }
    if (r < N) {
      double s0 = 0.0;
      for (int i = 0; i < R; ++i) s0 += wi[i] * pc[i][r] + dwd[i * N + r] * dc[i];
      o[r] = s0;
    }
  }
}

/// Raises every mu_j below `floor` to it and takes the mass proportionally from the others, so
/// that the floored entries stay exactly at the floor after renormalisation (a mode can come
/// back after a long run of bad luck). No-op for floor <= 0 or floor * R >= 1.
template <int R>
void apply_floor(Vector<R>& mu, double floor) {
  if (!(floor > 0.0) || floor * R >= 1.0) return;
  double fixed = 0.0, free = 0.0;
  for (int j = 0; j < R; ++j) (mu(j) < floor ? fixed : free) += (mu(j) < floor ? floor : mu(j));
  if (!(free > 0.0)) return;
  const double scale = (1.0 - fixed) / free;
  for (int j = 0; j < R; ++j) mu(j) = mu(j) < floor ? floor : mu(j) * scale;
}

}  // namespace ctxfuse::imm::detail

// The correction step shared by the EKF and the error-state EKF: from prior covariance,
// measurement Jacobian, innovation and noise to the state correction and the posterior
// covariance, with NIS, log-likelihood and the gate decision. Nothing here writes to the
// caller's estimate: the filters commit the result only when the status is accepted.
#pragma once

#include <cmath>

#include "ctxfuse/core/block_sparsity.hpp"
#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse::detail {

/// out += Q on the lower triangle (diagonal included); true when the lower triangle of the sum
/// is finite. The strict upper triangle of neither is read (`out`'s may be uninitialised).
template <int N>
bool add_lower_all_finite(SquareMatrix<N>& out, const SquareMatrix<N>& Q) {
  // The sum of all the elements is finite only when every element is (one Inf or NaN makes it
  // Inf or NaN), so one add per element settles the usual case; only when the sum is not
  // finite (a non-finite element, or finite ones near the largest double) are the elements
  // tested one by one.
  double total = 0.0;
  static_for<N>([&](auto jc) {
    constexpr int j = static_cast<int>(decltype(jc)::value);
    auto seg = out.col(j).template segment<N - j>(j);
    seg += Q.col(j).template segment<N - j>(j);
    total += seg.sum();
  });
  if (std::isfinite(total)) return true;
  for (int j = 0; j < N; ++j)
    for (int i = j; i < N; ++i)
      if (!std::isfinite(out(i, j))) return false;
  return true;
}

/// dst = the symmetric matrix whose lower triangle is src's: the lower triangle copied by
/// columns, then mirrored in place (src's strict upper triangle is not read).
template <int N>
void assign_lower_mirrored(const SquareMatrix<N>& src, SquareMatrix<N>& dst) {
  static_for<N>([&](auto jc) {
    constexpr int j = static_cast<int>(decltype(jc)::value);
    dst.col(j).template segment<N - j>(j) = src.col(j).template segment<N - j>(j);
  });
  symmetrize(dst);
}

/// Lower triangle of F P F' (see congruence_lower: with a pattern, the block-lower part and
/// the strict upper triangle untouched), block-sparse when the model declares
/// `transition_blocks`.
template <class Model, int N>
void propagate_covariance_lower(const SquareMatrix<N>& F, const SquareMatrix<N>& P, SquareMatrix<N>& out) {
  if constexpr (requires { Model::transition_blocks; }) {
    static_assert(decltype(Model::transition_blocks)::layout::size == N);
    congruence_lower<Model::transition_blocks>(F, P, out);
  } else {
    // Coefficient-based products: Eigen's default for N x N products of this size is its
    // blocked GEMM, whose packing costs more than the arithmetic.
    const SquareMatrix<N> FP = F.lazyProduct(P);
    out.noalias() = FP.lazyProduct(F.transpose());
  }
}

/// F P F', block-sparse when the model declares `transition_blocks`.
template <class Model, int N>
SquareMatrix<N> propagate_covariance(const SquareMatrix<N>& F, const SquareMatrix<N>& P) {
  SquareMatrix<N> out;
  propagate_covariance_lower<Model>(F, P, out);
  symmetrize(out);
  return out;
}

/// P <- G P G' after an error-state reset, for a symmetric P of which only the LOWER triangle
/// is read and written (the strict upper one is unspecified on return; callers symmetrise).
/// Block-sparse when the model declares `reset_blocks`; a block-diagonal pattern (the usual
/// case: only the attitude block of G differs from I) is applied to the affected block rows
/// and columns in place.
template <class Model, int N>
void reset_covariance_lower_in_place(const SquareMatrix<N>& G, SquareMatrix<N>& P) {
  if constexpr (requires { Model::reset_blocks; }) {
    static_assert(decltype(Model::reset_blocks)::layout::size == N);
    if constexpr (is_block_diagonal(Model::reset_blocks)) {
      block_diagonal_congruence_lower_in_place<Model::reset_blocks>(G, P);
      return;
    }
  }
  symmetrize(P);
  SquareMatrix<N> out;
  if constexpr (requires { Model::reset_blocks; }) {
    congruence_lower<Model::reset_blocks>(G, P, out);
  } else {
    const SquareMatrix<N> GP = G.lazyProduct(P);
    out.noalias() = GP.lazyProduct(G.transpose());
  }
  P = out;
}

/// G P G' after an error-state reset, block-sparse when the model declares `reset_blocks`.
template <class Model, int N>
SquareMatrix<N> reset_covariance(const SquareMatrix<N>& G, const SquareMatrix<N>& P) {
  SquareMatrix<N> out = P;
  reset_covariance_lower_in_place<Model>(G, out);
  symmetrize(out);
  return out;
}

/// P H' and the innovation covariance S = H P H' + R (symmetrised). `Meas` only matters for its
/// optional `jacobian_columns`: the blocks of the state its Jacobian can touch, so that the
/// products skip the columns that are zero. The update and score() (filters/score.hpp) both
/// compute S here, so a score's NIS is the update's to the last bit.
template <class Meas, int N, int M>
void innovation_covariance(const SquareMatrix<N>& P, const Matrix<M, N>& H, const SquareMatrix<M>& R,
                           Matrix<N, M>& PHt, SquareMatrix<M>& S) {
  if constexpr (requires { Meas::jacobian_columns; }) {
    static_assert(decltype(Meas::jacobian_columns)::layout::size == N, "jacobian_columns over another layout");
    PHt = times_transpose_columns<Meas::jacobian_columns>(P, H);
    S = columns_times<Meas::jacobian_columns>(H, PHt);
  } else {
    PHt.noalias() = P.lazyProduct(H.transpose());
    S.noalias() = H.lazyProduct(PHt);
  }
  S += R;
  symmetrize(S);
}

/// The innovation's statistics (dof, NIS, log N(y; 0, S)) and the gate's verdict: outcome
/// `gated` when the gate refuses, else accepted. The update and score() share it.
template <int M, class Gate>
Status innovation_verdict(const InnovationSolve<M>& solve, const Vector<M>& y, const Gate& gate) {
  Status status;
  status.dof = M;
  status.nis = solve.nis(y);
  status.log_likelihood = solve.log_likelihood(status.nis);
  status.gate_threshold = gate.threshold(M);
  if (!(status.nis <= status.gate_threshold)) status.outcome = Outcome::gated;
  return status;
}

/// `Meas` only matters for its optional `jacobian_columns`: the blocks of the state its
/// Jacobian can touch, so that P H' and H P H' skip the columns that are zero.
/// On acceptance P_post holds the posterior covariance in its LOWER triangle only (its strict
/// upper triangle is unspecified): finish_covariance() mirrors it, after the reset if any.
template <class Meas, int N, int M, class Gate>
Status kalman_correction(const SquareMatrix<N>& P, const Matrix<M, N>& H, const Vector<M>& y,
                         const SquareMatrix<M>& R, const Gate& gate, Vector<N>& dx,
                         SquareMatrix<N>& P_post) {
  if (!all_finite(H) || !all_finite(y)) return Status::failure(Problem::non_finite_prediction);

  Matrix<N, M> PHt;
  SquareMatrix<M> S;
  innovation_covariance<Meas, N, M>(P, H, R, PHt, S);
  const InnovationSolve<M> solve(S);
  if (!solve.ok) return Status::failure(Problem::innovation_not_positive_definite);

  Status status = innovation_verdict<M>(solve, y, gate);
  if (!status.accepted()) return status;

  // K = P H' S^-1 by triangular solves with the Cholesky factor of S: no explicit inverse.
  const Matrix<N, M> K = solve.right_solve(PHt);
  dx.noalias() = K.lazyProduct(y);
  // Not yet symmetrised nor checked for finiteness: the filter does both once, after its
  // reset (if any), with finish_covariance().
  joseph_update_expanded_lower<N, M>(P, K, PHt, S, P_post);
  if (!all_finite(dx)) return Status::failure(Problem::non_finite_state);
  return status;
}

/// Mirror the lower triangle of a posterior covariance and check it; false when not finite.
template <int N>
bool finish_covariance(SquareMatrix<N>& P) {
  symmetrize(P);
  return all_finite(P);
}

template <class Meas, int M>
Vector<M> innovation(const Meas& meas, const Vector<M>& z, const Vector<M>& z_pred) {
  if constexpr (requires { { meas.residual(z, z_pred) } -> std::convertible_to<Vector<M>>; })
    return meas.residual(z, z_pred);
  else
    return z - z_pred;
}

template <class Meas, int M>
Problem model_check(const Meas& meas, const Vector<M>& z) {
  if constexpr (requires { { meas.check(z) } -> std::convertible_to<Problem>; })
    return meas.check(z);
  else
    return Problem::none;
}

template <class Model, class Input>
Problem model_input_check(const Model& model, const Input& u) {
  if constexpr (requires { { model.check_input(u) } -> std::convertible_to<Problem>; })
    return model.check_input(u);
  else
    return Problem::none;
}

}  // namespace ctxfuse::detail

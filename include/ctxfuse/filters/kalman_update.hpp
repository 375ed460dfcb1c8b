// The correction step shared by the EKF and the error-state EKF: from prior covariance,
// measurement Jacobian, innovation and noise to the state correction and the posterior
// covariance, with NIS, log-likelihood and the gate decision. Nothing here writes to the
// caller's estimate: the filters commit the result only when the status is accepted.
#pragma once

#include "ctxfuse/core/block_sparsity.hpp"
#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse::detail {

/// F P F', block-sparse when the model declares `transition_blocks`.
template <class Model, int N>
SquareMatrix<N> propagate_covariance(const SquareMatrix<N>& F, const SquareMatrix<N>& P) {
  if constexpr (requires { Model::transition_blocks; }) {
    static_assert(decltype(Model::transition_blocks)::layout::size == N);
    return congruence<Model::transition_blocks>(F, P);
  } else {
    return F * P * F.transpose();
  }
}

/// G P G' after an error-state reset, block-sparse when the model declares `reset_blocks`.
template <class Model, int N>
SquareMatrix<N> reset_covariance(const SquareMatrix<N>& G, const SquareMatrix<N>& P) {
  if constexpr (requires { Model::reset_blocks; }) {
    static_assert(decltype(Model::reset_blocks)::layout::size == N);
    return congruence<Model::reset_blocks>(G, P);
  } else {
    return G * P * G.transpose();
  }
}

/// `Meas` only matters for its optional `jacobian_columns`: the blocks of the state its
/// Jacobian can touch, so that P H' and H P H' skip the columns that are zero.
template <class Meas, int N, int M, class Gate>
Status kalman_correction(const SquareMatrix<N>& P, const Matrix<M, N>& H, const Vector<M>& y,
                         const SquareMatrix<M>& R, const Gate& gate, Vector<N>& dx,
                         SquareMatrix<N>& P_post) {
  if (!all_finite(H) || !all_finite(y)) return Status::failure(Problem::non_finite_prediction);

  Matrix<N, M> PHt;
  SquareMatrix<M> S;
  if constexpr (requires { Meas::jacobian_columns; }) {
    static_assert(decltype(Meas::jacobian_columns)::layout::size == N, "jacobian_columns over another layout");
    PHt = times_transpose_columns<Meas::jacobian_columns>(P, H);
    S = columns_times<Meas::jacobian_columns>(H, PHt);
  } else {
    PHt.noalias() = P * H.transpose();
    S.noalias() = H * PHt;
  }
  S += R;
  symmetrize(S);
  const InnovationSolve<M> solve(S);
  if (!solve.ok) return Status::failure(Problem::innovation_not_positive_definite);

  Status status;
  status.dof = M;
  status.nis = solve.nis(y);
  status.log_likelihood = solve.log_likelihood(status.nis);
  status.gate_threshold = gate.threshold(M);
  if (!(status.nis <= status.gate_threshold)) {
    status.outcome = Outcome::gated;
    return status;
  }

  // K = P H' S^-1, solved as (S^-1 (P H')')' since S is symmetric: no explicit inverse.
  const Matrix<N, M> K = solve.llt.solve(PHt.transpose()).transpose();
  dx.noalias() = K * y;
  // Not yet symmetrised nor checked for finiteness: the filter does both once, after its
  // reset (if any), with finish_covariance().
  P_post = joseph_update_expanded<N, M>(P, K, PHt, S);
  if (!all_finite(dx)) return Status::failure(Problem::non_finite_state);
  return status;
}

/// Symmetrise and check a posterior covariance; false when it is not finite.
template <int N>
bool finish_covariance(SquareMatrix<N>& P) {
  if (!all_finite(P)) return false;
  symmetrize(P);
  return true;
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

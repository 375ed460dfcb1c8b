// The correction step shared by the EKF and the error-state EKF: from prior covariance,
// measurement Jacobian, innovation and noise to the state correction and the posterior
// covariance, with NIS, log-likelihood and the gate decision. Nothing here writes to the
// caller's estimate: the filters commit the result only when the status is accepted.
#pragma once

#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse::detail {

template <int N, int M, class Gate>
Status kalman_correction(const SquareMatrix<N>& P, const Matrix<M, N>& H, const Vector<M>& y,
                         const SquareMatrix<M>& R, const Gate& gate, Vector<N>& dx,
                         SquareMatrix<N>& P_post) {
  if (!H.allFinite() || !y.allFinite()) return Status::failure(Problem::non_finite_prediction);

  const Matrix<N, M> PHt = P * H.transpose();
  SquareMatrix<M> S = H * PHt;
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
  P_post = joseph_update<N, M>(P, K, H, R);
  if (!dx.allFinite()) return Status::failure(Problem::non_finite_state);
  if (!P_post.allFinite()) return Status::failure(Problem::non_finite_covariance);
  return status;
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

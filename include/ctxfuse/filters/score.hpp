// A measurement scored against a belief without updating it: the normalised innovation squared
// (NIS), the innovation log-likelihood log N(y; 0, S) and the gate's verdict, computed exactly as
// the update computes them (same checks, same S), for data association, mode scoring or
// monitoring. The belief is taken by const reference: nothing changes.
#pragma once

#include <type_traits>

#include "ctxfuse/core/concepts.hpp"
#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"
#include "ctxfuse/core/validation.hpp"
#include "ctxfuse/filters/kalman_update.hpp"
#include "ctxfuse/policies/gating.hpp"

namespace ctxfuse {

namespace detail {
/// The point a measurement is predicted at: a Gaussian's mean, an error-state belief's nominal.
template <class B>
const auto& belief_point(const B& b) {
  if constexpr (requires { b.nominal; })
    return b.nominal;
  else
    return b.mean;
}
}  // namespace detail

/// What `update` would report for z, without updating: outcome `accepted` when the gate would
/// let the measurement through, `gated` when it would refuse it, with `nis`, `gate_threshold`,
/// `log_likelihood` and `dof` filled in; `invalid_input` and `numerical_failure` with the same
/// Problem the update would name. `belief` is a Gaussian (EKF) or an error-state belief (ESKF).
template <class Meas, class B, GatePolicy Gate = policies::NoGate>
Status score(const Meas& meas, const B& belief, const Vector<Meas::dim>& z, const Gate& gate = {},
             const FilterOptions& opts = {}) {
  constexpr int M = Meas::dim;
  constexpr int N = std::remove_cvref_t<decltype(belief.cov)>::RowsAtCompileTime;
  const auto& x = detail::belief_point(belief);
  const SquareMatrix<M> R = meas.noise(x);
  if (Problem p = check_measurement<M>(z, R, opts); p != Problem::none) return Status::invalid(p);
  if (Problem p = detail::model_check(meas, z); p != Problem::none) return Status::invalid(p);
  if constexpr (requires { belief.mean; })
    if (!all_finite(belief.mean)) return Status::invalid(Problem::non_finite_prior);

  Matrix<M, N> H;
  const Vector<M> z_pred = meas.predict(x, &H);
  const Vector<M> y = detail::innovation(meas, z, z_pred);
  if (!all_finite(H) || !all_finite(y)) return Status::failure(Problem::non_finite_prediction);
  Matrix<N, M> PHt;
  SquareMatrix<M> S;
  detail::innovation_covariance<Meas, N, M>(belief.cov, H, R, PHt, S);
  const InnovationSolve<M> solve(S);
  if (!solve.ok) return Status::failure(Problem::innovation_not_positive_definite);

  return detail::innovation_verdict<M>(solve, y, gate);
}

/// z of a size known only at run time: refused with measurement_wrong_size unless it is
/// Meas::dim x 1 (core/validation.hpp).
template <class Meas, class B, DynamicSizeEigen Z, GatePolicy Gate = policies::NoGate>
Status score(const Meas& meas, const B& belief, const Z& z, const Gate& gate = {}, const FilterOptions& opts = {}) {
  return with_size_checked<Vector<Meas::dim>>(z, Problem::measurement_wrong_size,
                                              [&](const Vector<Meas::dim>& fixed) { return score(meas, belief, fixed, gate, opts); });
}

}  // namespace ctxfuse

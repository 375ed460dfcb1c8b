// The Rauch-Tung-Striebel kernel shared by the whole-run recorder (filters/rts.hpp, error-state
// beliefs, means and covariances smoothed) and the fixed-lag ring (filters/fixed_lag_rts.hpp,
// vector states, means only): the gain from one record to the next and the rule for a record
// at the newest record's time. One place, so the two smoothers cannot drift apart.
//
// Gain from record k (filtered covariance P) to record k+1 (prior covariance Pbar, transition
// Phi from k's posterior to k+1's prior):
//   C = P Phi' Pbar^-1,  computed as C' = Pbar^-1 (Phi P) by a Cholesky solve.
// A state held by construction (an augmented block with zero prior variance and zero process
// noise: a lever arm given as known, a scale factor not estimated) has exact zero rows and
// columns in every covariance, so Pbar is singular. Such a state is decoupled from the others
// (Pbar_jj = 0 forces (Phi P)_j = 0 for a positive semi-definite P), and the RTS solution of
// the others is the one without it; the solve puts 1 on its diagonal, which gives it a zero
// gain and leaves every other gain as in the reduced problem. A zero variance whose row is not
// zero is no covariance: refused.
#pragma once

#include <Eigen/Cholesky>

#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse {

/// C = P Phi' Pbar^-1 (above) into `C`; written only on success. Failure with
/// covariance_not_positive_definite when Pbar is not positive definite apart from held states,
/// non_finite_covariance when the gain is not finite.
template <int N>
Status rts_gain(const SquareMatrix<N>& P, const SquareMatrix<N>& Phi, const SquareMatrix<N>& Pbar, SquareMatrix<N>& C) {
  const SquareMatrix<N>* pbar = &Pbar;
  SquareMatrix<N> without_held;
  for (int j = 0; j < N; ++j) {
    if (Pbar(j, j) != 0.0) continue;
    if (!Pbar.row(j).isZero(0.0)) return Status::failure(Problem::covariance_not_positive_definite);
    if (pbar == &Pbar) without_held = Pbar;
    pbar = &without_held;
    without_held(j, j) = 1.0;
  }
  const Eigen::LLT<SquareMatrix<N>> llt(*pbar);
  if (llt.info() != Eigen::Success) return Status::failure(Problem::covariance_not_positive_definite);
  const SquareMatrix<N> gain = llt.solve(Phi * P).transpose();
  if (!all_finite(gain)) return Status::failure(Problem::non_finite_covariance);
  C = gain;
  return Status{};
}

/// The one rule for a record at or before the newest record's time t_last, with `phi` the
/// transition composed since it: an update at that same time with no prediction since (phi
/// the identity) joins the newest record (its prior stays the one before the first update);
/// anything else at or before t_last is out of order.
enum class RtsRecordKind { next, joins_newest, out_of_order };

template <int N>
RtsRecordKind rts_record_kind(double t, double t_last, const SquareMatrix<N>& phi) {
  if (t > t_last) return RtsRecordKind::next;
  if (t == t_last && phi.isIdentity(0.0)) return RtsRecordKind::joins_newest;
  return RtsRecordKind::out_of_order;
}

}  // namespace ctxfuse

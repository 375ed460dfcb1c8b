// Mixing policies of the IMM (filters/imm.hpp): where the mode transition matrix of each
// cycle comes from. A policy is a small value type with `SquareMatrix<R> matrix() const`
// (row-stochastic, rows = from, columns = to, entries per IMM cycle); the region-aware ones
// also take the recognised region of each cycle. Mode j is identified with region j
// (0 outdoor, 1 transition, 2 indoor in the region paper), so R is both counts.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <string>

#include "ctxfuse/core/error.hpp"
#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse::policies {

// Each constructor below that can be given a bad setting has a check function beside it that
// returns a SettingCheck (core/error.hpp: the Problem and the setting in words) instead of
// throwing: for code built without exceptions, or that must not stop on a configuration error.

/// Problem::transition_matrix_not_stochastic unless every entry is finite and >= 0 and every
/// row sums to 1 (within 1e-9).
template <int R>
SettingCheck check_transition(const SquareMatrix<R>& P) {
  const ctxfuse::detail::StochasticFault f = ctxfuse::detail::first_stochastic_fault<R>(P);
  if (f.row < 0) return {};
  if (f.col >= 0) return {Problem::transition_matrix_not_stochastic, "transition matrix: an entry is negative or not finite"};
  return {Problem::transition_matrix_not_stochastic, "transition matrix: a row does not sum to 1"};
}

namespace detail {
/// check_transition's verdict as invalid_setting, naming the entry or the row and its sum.
template <int R>
void require_row_stochastic(const SquareMatrix<R>& P, const char* who) {
  const ctxfuse::detail::StochasticFault f = ctxfuse::detail::first_stochastic_fault<R>(P);
  if (f.row < 0) return;
  if (f.col >= 0)
    ctxfuse::detail::invalid_setting(std::string(who) + ": entry (" + std::to_string(f.row) + ", " +
                                     std::to_string(f.col) + ") is negative or not finite");
  ctxfuse::detail::invalid_setting(std::string(who) + ": row " + std::to_string(f.row) + " sums to " +
                                   std::to_string(f.sum) + ", not 1");
}
}  // namespace detail

/// The textbook IMM: one fixed transition matrix.
template <int R>
struct FixedTransition {
  SquareMatrix<R> P = SquareMatrix<R>::Identity();

  FixedTransition() = default;
  explicit FixedTransition(const SquareMatrix<R>& p) : P(p) { detail::require_row_stochastic<R>(P, "FixedTransition"); }
  const SquareMatrix<R>& matrix() const { return P; }
  void observe_region(int) {}  // a fixed matrix ignores the recognised region
};

/// Problem::invalid_setting unless 0 <= stay <= 1.
inline SettingCheck check_sticky(double stay) {
  return stay >= 0.0 && stay <= 1.0 ? SettingCheck{} : SettingCheck::refuse("stay must be within [0, 1]");
}

/// Diagonal-dominant matrix: stay with probability `stay`, the rest spread evenly.
template <int R>
SquareMatrix<R> sticky_transition(double stay) {
  ctxfuse::detail::require_setting(check_sticky(stay), "sticky_transition");
  SquareMatrix<R> P = SquareMatrix<R>::Constant(R > 1 ? (1.0 - stay) / (R - 1) : 0.0);
  P.diagonal().setConstant(R > 1 ? stay : 1.0);
  return P;
}

/// Region-adaptive matrix of the region paper (eq. 36-39): P_m = w_p P + w_m M with M the
/// transition frequencies of the recognised region sequence, m_ij = c_ij / sum_j c_ij.
/// Window = 0 counts cumulatively since construction; Window = W > 0 counts only the last W
/// transitions (a ring of W + 1 labels), so M follows a change of driving pattern. A row of M
/// without counts (region never left, or never seen) is the identity row: with no evidence a
/// region is taken to persist. w_p + w_m must be 1 so that P_m stays row-stochastic; with
/// w_m = 0 the policy is exactly FixedTransition{P}. Nothing allocates.
template <int R, int Window = 0>
class RegionAdaptiveTransition {
 public:
  static_assert(Window >= 0);

  /// What the constructor would refuse: a prior that is not row-stochastic
  /// (transition_matrix_not_stochastic), weights not >= 0 or not summing to 1 (invalid_setting).
  static SettingCheck check(const SquareMatrix<R>& prior, double w_p, double w_m) {
    if (const SettingCheck c = check_transition<R>(prior); !c) return c;
    if (!(w_p >= 0.0 && w_m >= 0.0 && std::abs(w_p + w_m - 1.0) <= 1e-12))
      return SettingCheck::refuse("weights: need w_p >= 0, w_m >= 0 and w_p + w_m = 1");
    return {};
  }

  RegionAdaptiveTransition(const SquareMatrix<R>& prior, double w_p, double w_m) : prior_(prior), w_p_(w_p), w_m_(w_m) {
    detail::require_row_stochastic<R>(prior_, "RegionAdaptiveTransition prior");
    if (!check(prior, w_p, w_m))
      ctxfuse::detail::invalid_setting("RegionAdaptiveTransition: need w_p >= 0, w_m >= 0 and w_p + w_m = 1 (got " +
                                       std::to_string(w_p) + ", " + std::to_string(w_m) + ")");
    counts_.setZero();
  }

  /// Feeds the recognised region of the next cycle; a label outside [0, R) (unknown) breaks
  /// the chain: no transition is counted into or out of it.
  void observe_region(int label) {
    const bool valid = label >= 0 && label < R;
    if constexpr (Window > 0) {
      // Forget the oldest transition once the window is full.
      if (filled_ == Window + 1) {
        const int a = ring_[static_cast<std::size_t>(head_)];
        const int b = ring_[static_cast<std::size_t>((head_ + 1) % (Window + 1))];
        if (a >= 0 && b >= 0) counts_(a, b) -= 1.0;
        head_ = (head_ + 1) % (Window + 1);
        --filled_;
      }
      const int tail = (head_ + filled_) % (Window + 1);
      ring_[static_cast<std::size_t>(tail)] = valid ? label : -1;
      ++filled_;
    }
    if (valid && previous_ >= 0) counts_(previous_, label) += 1.0;
    previous_ = valid ? label : -1;
  }

  /// M (eq. 37).
  SquareMatrix<R> recognised_matrix() const {
    SquareMatrix<R> M;
    for (int i = 0; i < R; ++i) {
      const double n = counts_.row(i).sum();
      if (n > 0.0) {
        M.row(i) = counts_.row(i) / n;
      } else {
        M.row(i).setZero();
        M(i, i) = 1.0;
      }
    }
    return M;
  }

  /// P_m (eq. 38).
  SquareMatrix<R> matrix() const { return w_p_ * prior_ + w_m_ * recognised_matrix(); }

  const SquareMatrix<R>& counts() const { return counts_; }
  const SquareMatrix<R>& prior() const { return prior_; }
  double prior_weight() const { return w_p_; }
  double recognised_weight() const { return w_m_; }

 private:
  SquareMatrix<R> prior_;
  double w_p_, w_m_;
  SquareMatrix<R> counts_;
  int previous_ = -1;
  std::array<int, static_cast<std::size_t>(Window + 1)> ring_{};
  int head_ = 0, filled_ = 0;
};

/// Extension beyond the paper: pulls every row of a base policy's matrix toward the region
/// classifier's posterior pi (e.g. the HMM forward filter's), P' = (1 - lambda) P_base +
/// lambda 1 pi'. The mixing then moves probability toward the modes the classifier believes
/// in, softly (lambda < 1 keeps the filter's own evidence in charge). Row-stochastic whenever
/// P_base is and pi is a distribution; a posterior that is not one (NaN, negative, zero sum)
/// is ignored and the base matrix used as is.
template <int R, class Base>
class PosteriorPull {
 public:
  /// Problem::invalid_setting unless 0 <= lambda <= 1.
  static SettingCheck check(double lambda) {
    return lambda >= 0.0 && lambda <= 1.0 ? SettingCheck{} : SettingCheck::refuse("lambda must be within [0, 1]");
  }

  PosteriorPull(Base base, double lambda) : base_(std::move(base)), lambda_(lambda) {
    ctxfuse::detail::require_setting(check(lambda), "PosteriorPull");
    posterior_.setConstant(1.0 / R);
  }

  void observe_region(int label) { base_.observe_region(label); }

  void observe_posterior(const Vector<R>& pi) {
    const double s = pi.sum();
    if (!pi.allFinite() || (pi.array() < 0.0).any() || !(s > 0.0)) {
      valid_ = false;
      return;
    }
    posterior_ = pi / s;
    valid_ = true;
  }

  SquareMatrix<R> matrix() const {
    SquareMatrix<R> P = base_.matrix();
    if (!valid_) return P;
    return (1.0 - lambda_) * P + lambda_ * Vector<R>::Ones() * posterior_.transpose();
  }

  Base& base() { return base_; }
  const Base& base() const { return base_; }

 private:
  Base base_;
  double lambda_;
  Vector<R> posterior_;
  bool valid_ = false;
};

}  // namespace ctxfuse::policies

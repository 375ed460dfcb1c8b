// Health of one aiding source in one filter, and the recovery from a gate lock-out.
//
// A chi-square gate protects a filter from outliers only while the filter's covariance covers
// its real error. After a stretch of dead reckoning or a few biased measurements the error can
// outgrow the covariance; the gate then rejects the good measurements too, and nothing ever
// brings the filter back (a tight gate "locks it out"). Loosening the gate is no cure: it lets
// the outliers in all the time. The cure used by production filters (PX4's EKF2 keeps a
// per-source rejection timer and resets the states that source observes) is to keep the gate
// tight and to notice the lock-out: a source that keeps delivering measurements and has had
// every one rejected for longer than a timeout says more about the filter than about itself.
// The filter then widens the covariance of the blocks that source observes, so that the next
// measurement is judged against an honest uncertainty.
//
// `SourceHealth` is the bookkeeping (what PX4 calls the innovation-check-fail timer) for one
// source in one filter. The recovery widens the covariance of a named block, by one of two
// amounts: a fixed sigma (`widen_block`), or just enough that the refused innovation lies on
// the gate's boundary (`variance_to_gate`; filters/release.hpp applies it and updates). Every
// pipeline's lock-out goes through this header: the GNSS/INS pass and its simulation study
// release by `variance_to_gate` after a count of refusals in a row (timeout 0), the region
// IMM and the NLOS UWB run widen by a fixed sigma after a timeout.
#pragma once

#include <limits>

#include <Eigen/Cholesky>

#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse::policies {

struct SourceHealthOptions {
  /// A lock-out is declared when every measurement of the source was rejected for this long ...
  double timeout_s = 2.0;
  /// ... and at least this many were rejected by the gate in that time (a source that merely
  /// went silent, e.g. GNSS in a garage, is not a lock-out).
  int min_rejections = 5;
};

class SourceHealth {
 public:
  SourceHealth() = default;
  explicit SourceHealth(SourceHealthOptions options) : options_(options) {}

  /// Records the outcome of one update of this source at time t. Only accepted and gated
  /// outcomes count: invalid input says nothing about the filter.
  void record(double t, const Status& s) {
    if (s.accepted()) {
      rejections_ = 0;
      return;
    }
    if (s.outcome != Outcome::gated) return;
    if (rejections_ == 0) first_rejection_t_ = t;
    ++rejections_;
  }

  /// True when the source has been locked out: an unbroken run of at least `min_rejections`
  /// rejected measurements, none accepted, whose first rejection is more than `timeout_s` ago.
  /// An acceptance or a recovery ends the run, so the run never starts before either. A burst
  /// of rejections after a long silence is therefore not yet a lock-out.
  bool lockout(double t) const {
    return rejections_ >= options_.min_rejections && t - first_rejection_t_ > options_.timeout_s;
  }

  /// Starts a new count after the caller has recovered (widened the covariance).
  void recovered() { rejections_ = 0; }

  int rejections() const { return rejections_; }
  const SourceHealthOptions& options() const { return options_; }

 private:
  SourceHealthOptions options_;
  double first_rejection_t_ = -std::numeric_limits<double>::infinity();
  int rejections_ = 0;
};

/// Adds sigma^2 to the diagonal of the named block of P: the recovery from a lock-out. Adding
/// a positive semi-definite term keeps P a covariance, keeps the estimate itself and its
/// correlations, and only says "the error in this block may be this much larger".
template <class ErrorLayout, FixedString Name, int N>
void widen_block(SquareMatrix<N>& P, double sigma) {
  static_assert(ErrorLayout::size == N, "covariance of another layout");
  ErrorLayout::template cov<Name>(P).diagonal().array() += sigma * sigma;
}

/// The variance a >= 0 to add to each axis of one block of the covariance so that the
/// innovation y lies on the gate's boundary: y' (S0 + a dS)^-1 y = limit, where S0 is the
/// innovation covariance and dS = Hb Hb' the derivative of S with respect to a (Hb: the
/// measurement Jacobian's columns of the block). 0 when y already lies inside the gate. The
/// NIS falls monotonically with a: the root is bracketed (a from 1e-4, times 4, at most 1e12)
/// and bisected 40 times; the upper end is returned, so the widened innovation is never
/// outside the gate. NaN when y, S0 or dS is not finite.
template <int M>
double variance_to_gate(const Vector<M>& y, const SquareMatrix<M>& S0, const SquareMatrix<M>& dS, double limit) {
  if (!y.allFinite() || !S0.allFinite() || !dS.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  auto nis = [&](double added) {
    const SquareMatrix<M> S = S0 + added * dS;
    return y.dot(S.ldlt().solve(y));
  };
  if (!(nis(0.0) > limit)) return 0.0;
  double lo = 0.0, hi = 1e-4;
  while (nis(hi) > limit && hi < 1e12) lo = hi, hi *= 4.0;
  for (int i = 0; i < 40; ++i) {
    const double mid = 0.5 * (lo + hi);
    (nis(mid) > limit ? lo : hi) = mid;
  }
  return hi;
}

}  // namespace ctxfuse::policies

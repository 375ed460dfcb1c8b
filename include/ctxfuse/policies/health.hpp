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
// source in one filter; `widen_blocks` is the recovery, on a covariance laid out by block names.
#pragma once

#include <limits>

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

}  // namespace ctxfuse::policies

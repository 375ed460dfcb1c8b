// Integrity of a position estimate against independent position snapshots (e.g. a UWB
// multilateration of one epoch's ranges), and the evidence to re-anchor a filter that has
// settled on a wrong solution.
//
// Why the lock-out recovery of policies/health.hpp is not enough. A range-aided filter that
// sees only two anchors cannot tell its track from the track's mirror image about the line
// through them. Once it is on the mirror (entering a building a few metres behind the truth
// is enough) the two anchors' ranges keep being accepted there, so no lock-out is ever
// declared, and the motion that fits the mirror is the true motion reflected: the filter runs
// away backwards, tens of metres, with a small covariance (scenario "paper", seed 3, the
// federated filter: 36.6 m mean error). Only a position that does not come through the filter
// can show it: a snapshot from enough anchors to be unambiguous.
//
// The check. A snapshot disagrees with the estimate when (i) the chi-square test on the
// difference with both covariances fails at `probability` and (ii) the difference is a gross
// error of more than `min_error_m`. A snapshot that passes either test agrees, and ends any
// run of disagreements. `consecutive` disagreeing snapshots in a row are a fault.
//
// Why both tests and a run. Snapshots are not outlier-free: a line-of-sight-looking NLOS range
// among four shifts the solution by 0.5-3 m with a covariance that does not know it, and then
// the chi-square test alone disagrees with a good filter for many epochs in a row (default
// scenario, a federated filter on its track: 27-50 snapshots per drive, runs of up to 16). A filter within a few metres of the
// truth is the lock-out recovery's business; the gross-error floor keeps this check to the
// failures that recovery cannot see. The run keeps one unlucky snapshot from moving a filter.
#pragma once

#include <cmath>
#include <optional>

#include <Eigen/Cholesky>

#include "ctxfuse/core/error.hpp"
#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse::policies {

struct SnapshotIntegrityOptions {
  double probability = 0.999;  // chi-square test of estimate against snapshot
  double min_error_m = 5.0;    // ... and a gross error: farther apart than this
  int consecutive = 3;         // disagreeing snapshots in a row that make a fault
};

/// The option that is out of range, or nullptr when all are in range.
inline const char* invalid_option(const SnapshotIntegrityOptions& o) {
  if (!(o.probability > 0.0 && o.probability < 1.0)) return "SnapshotIntegrity: probability must be in (0, 1)";
  if (!(o.min_error_m >= 0.0) || !std::isfinite(o.min_error_m))
    return "SnapshotIntegrity: min_error_m must be finite and >= 0";
  if (o.consecutive < 1) return "SnapshotIntegrity: consecutive must be >= 1";
  return nullptr;
}

/// Problem::invalid_setting naming the option out of range (what SnapshotIntegrity's
/// constructor refuses), or accepted.
inline SettingCheck check_options(const SnapshotIntegrityOptions& o) {
  const char* what = invalid_option(o);
  return what ? SettingCheck::refuse(what) : SettingCheck{};
}

namespace detail {
/// The constructor's check: throws std::invalid_argument naming the option (core/error.hpp).
inline void require_options(const SnapshotIntegrityOptions& o) {
  if (const char* what = invalid_option(o)) ctxfuse::detail::invalid_setting(what);
}
}  // namespace detail

template <int D>
class SnapshotIntegrity {
 public:
  /// What a fault hands the caller to re-anchor with: the last snapshot and, when the run
  /// spans time, the mean velocity between its first and last snapshots (the filter's own
  /// velocity is untrustworthy then: on a mirror track it is the true one reflected).
  struct Fault {
    double t = 0.0;
    Vector<D> position;
    SquareMatrix<D> cov;
    std::optional<Vector<D>> velocity;
    double span_s = 0.0;  // time between the first and last snapshot of the run
  };

  SnapshotIntegrity() : SnapshotIntegrity(SnapshotIntegrityOptions{}) {}
  explicit SnapshotIntegrity(SnapshotIntegrityOptions options)
      : options_(options), threshold_((detail::require_options(options), chi_square_quantile(options.probability, D))) {}

  /// Compares the snapshot (position, covariance) taken at time t with the estimate and its
  /// covariance. Returns a fault after `consecutive` disagreements in a row, and starts a new
  /// run. Inputs that are not finite, a covariance sum that is not positive definite, or time
  /// going backwards are ignored (nothing counted, the run kept).
  std::optional<Fault> check(double t, const Vector<D>& snapshot, const SquareMatrix<D>& snapshot_cov,
                             const Vector<D>& estimate, const SquareMatrix<D>& estimate_cov) {
    if (!std::isfinite(t) || !all_finite(snapshot) || !all_finite(snapshot_cov) || !all_finite(estimate) ||
        !all_finite(estimate_cov))
      return std::nullopt;
    if (run_ > 0 && t < last_t_) return std::nullopt;
    const Vector<D> diff = snapshot - estimate;
    const Eigen::LLT<SquareMatrix<D>> llt(snapshot_cov + estimate_cov);
    if (llt.info() != Eigen::Success) return std::nullopt;
    const double d2 = diff.dot(llt.solve(diff));
    last_d2_ = d2;
    if (!(d2 > threshold_ && diff.norm() > options_.min_error_m)) {
      run_ = 0;
      return std::nullopt;
    }
    if (run_ == 0) {
      first_t_ = t;
      first_ = snapshot;
    }
    ++run_;
    last_t_ = t;
    if (run_ < options_.consecutive) return std::nullopt;
    Fault f;
    f.t = t;
    f.position = snapshot;
    f.cov = snapshot_cov;
    f.span_s = t - first_t_;
    if (f.span_s > 0.0) f.velocity = Vector<D>((snapshot - first_) / f.span_s);
    run_ = 0;
    return f;
  }

  int run() const { return run_; }
  double threshold() const { return threshold_; }
  double last_d2() const { return last_d2_; }
  const SnapshotIntegrityOptions& options() const { return options_; }

 private:
  SnapshotIntegrityOptions options_;
  double threshold_;
  int run_ = 0;
  double first_t_ = 0.0, last_t_ = 0.0;
  Vector<D> first_ = Vector<D>::Zero();
  double last_d2_ = 0.0;
};

}  // namespace ctxfuse::policies

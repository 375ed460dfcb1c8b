// Measurement gating policies: a small type passed to the filter as a template argument. The
// filter computes the normalised innovation squared (NIS) and asks the policy for the
// threshold at the measurement's degrees of freedom; NIS above it means the update is gated.
#pragma once

#include <array>
#include <limits>

#include "ctxfuse/core/numerics.hpp"

namespace ctxfuse::policies {

/// Every measurement passes.
struct NoGate {
  constexpr double threshold(int /*dof*/) const { return std::numeric_limits<double>::infinity(); }
};

/// One-tailed chi-square test: reject when NIS exceeds the chi-square quantile at
/// `probability` for the measurement dimension. Quantiles for 1..kCached degrees of freedom
/// are computed once at construction, so the per-update cost is a table look-up.
class ChiSquareGate {
 public:
  static constexpr int kCached = 16;

  explicit ChiSquareGate(double probability = 0.99) : probability_(probability) {
    for (int dof = 1; dof <= kCached; ++dof) cache_[static_cast<std::size_t>(dof)] = chi_square_quantile(probability, dof);
  }

  double probability() const { return probability_; }

  double threshold(int dof) const {
    if (dof >= 1 && dof <= kCached) return cache_[static_cast<std::size_t>(dof)];
    return chi_square_quantile(probability_, dof);
  }

 private:
  double probability_;
  std::array<double, kCached + 1> cache_{};
};

/// A fixed NIS threshold, independent of the dimension (e.g. tuned by hand for one sensor).
struct FixedThresholdGate {
  double max_nis = std::numeric_limits<double>::infinity();
  constexpr double threshold(int /*dof*/) const { return max_nis; }
};

}  // namespace ctxfuse::policies

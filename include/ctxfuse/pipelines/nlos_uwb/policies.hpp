// The NLOS decision as a policy (issue 16 item 3): which ranges of one epoch enter the
// estimator, from the per-range verdicts of the classifiers (classifier.hpp). A policy is a
// small type passed to the run loop as a template argument:
//
//   void select(std::span<const RangeVerdict> epoch, std::span<bool> attach) const;
//
// - PaperEpochRule: the paper's rule for the epoch's UWB factor, all or nothing: attach when
//   every range is LOS; also when fewer than half of the ranges are NLOS and the D-S
//   probability R is above 0.7; otherwise leave the epoch's factor out. The paper does not say
//   which range's R; we read "the optimal probability R from D-S" as the probability D-S gives
//   to the hypothesis it chose, for every range of the epoch: max(R, 1 - R), and the epoch's
//   belief as the smallest of these (the mixed epoch is attached only when D-S is sure of
//   every range). A range without evidence (its anchor's first range: no range rate yet) is
//   LOS and does not enter the minimum.
// - PerRangeRule (the extension): leave out only the ranges judged NLOS.
// - NoNlosHandling: every range (the "without NLOS handling" baseline).
// - NlosPolicyChoice: one of the three, chosen at run time.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>

#include "ctxfuse/classify/consistency.hpp"

namespace ctxfuse::pipelines::nlos_uwb {

/// What the classifiers said about one range.
struct RangeVerdict {
  double p1 = std::nan("");  // SVM NLOS probability (NaN: no SVM or no range rate yet)
  double p2 = std::nan("");  // consistency NLOS probability (NaN: no range rate yet)
  double R = std::nan("");   // D-S fused NLOS belief (NaN: no evidence)
  bool nlos = false;         // R above the decision threshold (paper eq. 8: 0.8)
};

/// The D-S probability of the hypothesis chosen for the range; NaN without evidence.
inline double decision_confidence(const RangeVerdict& v) { return std::isnan(v.R) ? v.R : std::max(v.R, 1.0 - v.R); }

struct PaperEpochRule {
  classify::FactorAttachPolicy rule{};

  /// The epoch's belief passed to the attach rule: the smallest decision confidence (1 when
  /// no range carries evidence).
  static double epoch_belief(std::span<const RangeVerdict> epoch) {
    double b = 1.0;
    for (const auto& v : epoch)
      if (const double c = decision_confidence(v); !std::isnan(c)) b = std::min(b, c);
    return b;
  }

  void select(std::span<const RangeVerdict> epoch, std::span<bool> attach) const {
    const int n = static_cast<int>(epoch.size());
    const int nlos = static_cast<int>(std::count_if(epoch.begin(), epoch.end(), [](const RangeVerdict& v) { return v.nlos; }));
    const bool all = rule.attach(n, nlos, epoch_belief(epoch));
    std::fill(attach.begin(), attach.begin() + n, all);
  }
};

struct PerRangeRule {
  void select(std::span<const RangeVerdict> epoch, std::span<bool> attach) const {
    for (std::size_t i = 0; i < epoch.size(); ++i) attach[i] = !epoch[i].nlos;
  }
};

struct NoNlosHandling {
  void select(std::span<const RangeVerdict> epoch, std::span<bool> attach) const {
    std::fill(attach.begin(), attach.begin() + static_cast<std::ptrdiff_t>(epoch.size()), true);
  }
};

/// The three policies above as one run-time choice. A program that runs several of them (the
/// studies of studies/nlos_uwb*.hpp run every variant) compiles the run loop once per estimator
/// instead of once per estimator and policy; a policy is consulted once an epoch, so the
/// switch costs nothing measurable there.
enum class NlosHandling : std::uint8_t {
  paper_epoch_rule,  // PaperEpochRule
  per_range,         // PerRangeRule
  none,              // NoNlosHandling
};

struct NlosPolicyChoice {
  NlosHandling handling = NlosHandling::paper_epoch_rule;
  PaperEpochRule paper{};  // the rule's settings, used by paper_epoch_rule

  void select(std::span<const RangeVerdict> epoch, std::span<bool> attach) const {
    switch (handling) {
      case NlosHandling::paper_epoch_rule: paper.select(epoch, attach); return;
      case NlosHandling::per_range: PerRangeRule{}.select(epoch, attach); return;
      case NlosHandling::none: NoNlosHandling{}.select(epoch, attach); return;
    }
  }
};

template <class P>
concept NlosPolicy = requires(const P& p, std::span<const RangeVerdict> v, std::span<bool> a) { p.select(v, a); };

}  // namespace ctxfuse::pipelines::nlos_uwb

// Dempster-Shafer combination over the frame {NLOS, LOS} (NLOS paper, eq. 7-8).
// Each source gives a mass assignment m(NLOS), m(LOS) and optionally m(Theta) on the whole
// frame (its "don't know"). Dempster's rule multiplies the masses, discards the conflicting
// products (NLOS x LOS) and renormalises by K = 1 - conflict. With no mass on Theta and two
// sources this is exactly the paper's K = p1 p2 + q1 q2, R = p1 p2 / K. The rule is
// associative, so n sources are folded pairwise; the reported conflict is that of the n-way
// combination, 1 - prod(K_i).
// Total conflict (K = 0, e.g. one source certain NLOS, another certain LOS) is reported as a
// status (numerical failure, Problem::total_conflict), never divided by: the result then carries
// the vacuous assignment m(Theta) = 1. A mass that is not one is refused (invalid input,
// Problem::invalid_mass).
#pragma once

#include <cmath>
#include <span>

#include "ctxfuse/core/status.hpp"

namespace ctxfuse::classify {

struct BinaryMass {
  double nlos = 0.0;
  double los = 0.0;
  double either = 0.0;  // mass on the whole frame {NLOS, LOS}: the source's ignorance

  /// A Bayesian source: probability p of NLOS, 1 - p of LOS, no ignorance.
  static constexpr BinaryMass from_probability(double p_nlos) { return {p_nlos, 1.0 - p_nlos, 0.0}; }
  /// Belief in NLOS (mass committed to NLOS) and plausibility (mass not against NLOS).
  constexpr double belief_nlos() const { return nlos; }
  constexpr double plausibility_nlos() const { return nlos + either; }
};

struct DsResult {
  BinaryMass mass{0.0, 0.0, 1.0};
  /// Mass the sources put on contradictory hypotheses, 1 - K (0 = full agreement).
  double conflict = 0.0;
  Status status{};  // accepted, or why not (the core vocabulary of filters and classifiers)
  /// R of eq. 8: the combined NLOS mass.
  double nlos_belief() const { return mass.nlos; }
};

/// True when the masses are finite, non-negative and sum to 1 within 1e-9.
constexpr bool is_valid_mass(const BinaryMass& m) {
  const double sum = m.nlos + m.los + m.either;
  return std::isfinite(sum) && m.nlos >= 0.0 && m.los >= 0.0 && m.either >= 0.0 &&
         std::abs(sum - 1.0) <= 1e-9;
}

/// Dempster's rule for two sources.
inline DsResult combine(const BinaryMass& a, const BinaryMass& b) {
  DsResult r;
  if (!is_valid_mass(a) || !is_valid_mass(b)) {
    r.status = Status::invalid(Problem::invalid_mass);
    r.conflict = std::nan("");
    return r;
  }
  const double nlos = a.nlos * b.nlos + a.nlos * b.either + a.either * b.nlos;
  const double los = a.los * b.los + a.los * b.either + a.either * b.los;
  const double either = a.either * b.either;
  const double agreement = nlos + los + either;  // K
  r.conflict = a.nlos * b.los + a.los * b.nlos;
  if (!(agreement > 0.0)) {
    r.status = Status::failure(Problem::total_conflict);
    r.conflict = 1.0;
    return r;
  }
  r.mass = {nlos / agreement, los / agreement, either / agreement};
  return r;
}

/// Paper form: two NLOS probabilities p1, p2 -> R = p1 p2 / (p1 p2 + q1 q2).
inline DsResult combine_probabilities(double p1, double p2) {
  return combine(BinaryMass::from_probability(p1), BinaryMass::from_probability(p2));
}

/// n sources folded with Dempster's rule. An empty span gives the vacuous assignment.
inline DsResult combine(std::span<const BinaryMass> sources) {
  DsResult acc;  // vacuous: neutral element of the rule
  double agreement_product = 1.0;
  for (const auto& s : sources) {
    const DsResult next = combine(acc.mass, s);
    if (!next.status) {
      DsResult out = next;
      if (next.status.problem == Problem::total_conflict) out.conflict = 1.0;
      return out;
    }
    agreement_product *= 1.0 - next.conflict;
    acc.mass = next.mass;
  }
  acc.conflict = 1.0 - agreement_product;
  return acc;
}

}  // namespace ctxfuse::classify

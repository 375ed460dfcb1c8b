// Region transition matrix estimated from a recognised label sequence (region paper,
// eq. 36-37): c_ij counts the steps from region i to region j, m_ij = c_ij / sum_j c_ij.
// A region never left in the sequence has no counts in its row; what that row becomes is a
// policy: IdentityForEmptyRows (default: with no evidence the region is assumed to persist,
// which is what a region recogniser mostly sees) or UniformForEmptyRows (no preference).
// The counter is a fixed-size struct, so feeding labels online never allocates.
#pragma once

#include <Eigen/Core>

#include <span>

namespace ctxfuse::classify {

struct IdentityForEmptyRows {
  template <typename Row>
  static void fill(Row&& row, int i) {
    row.setZero();
    row[i] = 1.0;
  }
};

struct UniformForEmptyRows {
  template <typename Row>
  static void fill(Row&& row, int) {
    row.setConstant(1.0 / double(row.size()));
  }
};

template <int NumRegions, typename EmptyRowPolicy = IdentityForEmptyRows>
struct RegionTransitionCounter {
  using Matrix = Eigen::Matrix<double, NumRegions, NumRegions>;
  Matrix counts = Matrix::Zero();
  int previous = -1;

  /// Feeds the next recognised label; labels outside [0, NumRegions) (e.g. -1 = unknown)
  /// break the chain: no transition is counted into or out of them.
  void add(int label) {
    const bool valid = label >= 0 && label < NumRegions;
    if (valid && previous >= 0) counts(previous, label) += 1.0;
    previous = valid ? label : -1;
  }

  void add(std::span<const int> labels) {
    for (int l : labels) add(l);
  }

  /// Row-stochastic matrix m_ij (eq. 37) with EmptyRowPolicy for rows without counts.
  Matrix matrix() const {
    Matrix m;
    for (int i = 0; i < NumRegions; ++i) {
      const double row = counts.row(i).sum();
      if (row > 0.0)
        m.row(i) = counts.row(i) / row;
      else
        EmptyRowPolicy::fill(m.row(i), i);
    }
    return m;
  }
};

/// Convenience: the transition matrix of a whole label sequence.
template <int NumRegions, typename EmptyRowPolicy = IdentityForEmptyRows>
Eigen::Matrix<double, NumRegions, NumRegions> region_transition_matrix(std::span<const int> labels) {
  RegionTransitionCounter<NumRegions, EmptyRowPolicy> counter;
  counter.add(labels);
  return counter.matrix();
}

}  // namespace ctxfuse::classify

namespace ctxfuse::classify {

/// IMM transition update (region paper, eq. 38-39): P_m = w_p * P + (1 - w_p) * M. Both inputs
/// row-stochastic and 0 <= w_p <= 1 give a row-stochastic result; callers validate w_p.
template <int N>
Eigen::Matrix<double, N, N> blend_transition(const Eigen::Matrix<double, N, N>& prior,
                                             const Eigen::Matrix<double, N, N>& recognised,
                                             double prior_weight) {
  return prior_weight * prior + (1.0 - prior_weight) * recognised;
}

}  // namespace ctxfuse::classify

// Filter consistency by Monte Carlo (Bar-Shalom, Li & Kirubarajan, "Estimation with
// Applications to Tracking and Navigation", sec. 5.4): over R independent runs of the same
// scenario, a consistent filter's estimation error e_k with covariance P_k has
// NEES_k = e_k' P_k^-1 e_k ~ chi-square(n), so R times the run-average of NEES_k is
// chi-square(R n) and the average lies in [chi2_{R n}(a/2), chi2_{R n}(1 - a/2)] / R with
// probability 1 - a. The same holds for NIS with the measurement dimension m in place of n.
// An average above the band says the filter is over-confident (P too small: process or
// measurement noise under-stated, or a wrong Jacobian); below it, under-confident.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse::eval {

/// e' P^-1 e. NaN when P is not positive definite or anything is non-finite.
template <int N>
double nees(const Vector<N>& error, const SquareMatrix<N>& P) {
  if (!error.allFinite() || !P.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::LLT<SquareMatrix<N>> llt(P);
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::quiet_NaN();
  return error.dot(llt.solve(error));
}

struct ChiSquareBand {
  double lower = 0.0, upper = 0.0;
  bool contains(double average) const { return average >= lower && average <= upper; }
};

/// The two-sided `probability` band of the average of `runs` independent chi-square(dof)
/// statistics. Throws std::invalid_argument for dof or runs < 1 or probability outside (0, 1).
inline ChiSquareBand average_chi_square_band(int dof, int runs, double probability = 0.95) {
  if (dof < 1 || runs < 1) throw std::invalid_argument("average_chi_square_band: dof and runs must be >= 1");
  if (!(probability > 0.0 && probability < 1.0))
    throw std::invalid_argument("average_chi_square_band: probability must be within (0, 1)");
  const int total = dof * runs;
  const double tail = 0.5 * (1.0 - probability);
  return {chi_square_quantile(tail, total) / runs, chi_square_quantile(1.0 - tail, total) / runs};
}

/// Run-averages of a per-step statistic (NEES or NIS) over Monte Carlo runs. Steps may be
/// added in any order; a non-finite value is counted separately and kept out of the average
/// (a filter that produced it has failed, which `failures()` reports).
class MonteCarloAverage {
 public:
  explicit MonteCarloAverage(std::size_t steps) : sum_(steps, 0.0), count_(steps, 0) {}

  void add(std::size_t step, double value) {
    if (step >= sum_.size()) throw std::out_of_range("MonteCarloAverage: step " + std::to_string(step) + " beyond the " + std::to_string(sum_.size()) + " steps");
    if (!std::isfinite(value)) {
      ++failures_;
      return;
    }
    sum_[step] += value;
    ++count_[step];
  }

  std::size_t steps() const { return sum_.size(); }
  std::size_t runs_at(std::size_t step) const { return count_.at(step); }
  std::size_t failures() const { return failures_; }
  /// NaN for a step without values.
  double average(std::size_t step) const {
    return count_.at(step) ? sum_[step] / static_cast<double>(count_[step]) : std::numeric_limits<double>::quiet_NaN();
  }
  /// Share of the steps with values whose average lies inside `band`.
  double fraction_inside(const ChiSquareBand& band) const {
    std::size_t with = 0, inside = 0;
    for (std::size_t k = 0; k < sum_.size(); ++k) {
      if (!count_[k]) continue;
      ++with;
      inside += band.contains(average(k)) ? 1 : 0;
    }
    return with ? static_cast<double>(inside) / static_cast<double>(with) : 0.0;
  }
  /// Average over every step with values (the "time-averaged" statistic).
  double overall_average() const {
    double s = 0.0;
    std::size_t n = 0;
    for (std::size_t k = 0; k < sum_.size(); ++k) {
      s += sum_[k];
      n += count_[k];
    }
    return n ? s / static_cast<double>(n) : std::numeric_limits<double>::quiet_NaN();
  }

 private:
  std::vector<double> sum_;
  std::vector<std::size_t> count_;
  std::size_t failures_ = 0;
};

/// One statistic (NEES or NIS) of a Monte Carlo set against its chi-square bands.
///   per-epoch: the run-average at each epoch against the band of `runs` chi-square(dof)
///     values. For a consistent filter each epoch's average lies inside with probability
///     `probability`; neighbouring epochs are correlated, so the fraction inside scatters more
///     than a binomial count would.
///   time average: the average over every epoch and run against the band of that many
///     chi-square(dof) values. Exact for the NIS of a consistent linear-Gaussian filter (its
///     innovations are white, so independent over time); for the NEES, whose errors are
///     correlated over time, this band is narrower than the statistic's true spread and is
///     reported, not tested.
struct BandCheck {
  ChiSquareBand epoch_band, time_band;
  double fraction_inside = 0.0;  // share of epochs whose run-average lies in epoch_band
  double time_average = std::numeric_limits<double>::quiet_NaN();
  std::size_t failures = 0;      // non-finite values (a failed filter step)

  bool epochs_inside(double min_fraction) const { return failures == 0 && fraction_inside >= min_fraction; }
  bool time_average_inside() const { return failures == 0 && time_band.contains(time_average); }
};

/// `stat` against the bands of chi-square(dof), with `runs` runs per epoch (every epoch must
/// have that many values: a Monte Carlo set with missing runs is refused with
/// std::invalid_argument rather than judged against the wrong band).
inline BandCheck check_bands(const MonteCarloAverage& stat, int dof, int runs, double probability = 0.95) {
  std::size_t values = 0;
  for (std::size_t k = 0; k < stat.steps(); ++k) {
    if (stat.runs_at(k) != static_cast<std::size_t>(runs))
      throw std::invalid_argument("check_bands: epoch " + std::to_string(k) + " has " + std::to_string(stat.runs_at(k)) +
                                  " values, not " + std::to_string(runs));
    values += stat.runs_at(k);
  }
  BandCheck c;
  c.epoch_band = average_chi_square_band(dof, runs, probability);
  c.time_band = average_chi_square_band(dof, static_cast<int>(values), probability);
  c.fraction_inside = stat.fraction_inside(c.epoch_band);
  c.time_average = stat.overall_average();
  c.failures = stat.failures();
  return c;
}

}  // namespace ctxfuse::eval

// Hidden Markov model over discrete regions with Gaussian emissions (region paper, eq. 14-17):
// supervised estimation from labelled sequences, Viterbi decoding of a batch and an online
// forward filter giving the region posterior each epoch.
//
// Everything runs in the log domain: with a few hundred epochs the linear-domain forward
// variables underflow double precision, and Viterbi scores of long runs differ by hundreds
// of nats. Emission densities are multivariate normal; the covariance is full by default or
// diagonal (CovarianceKind::diagonal drops the off-diagonal terms at estimation time, which
// helps when a region has few samples). Both are stored as a full matrix plus its Cholesky
// factor, so evaluation is the same code for both.
//
// Errors: building or fitting a model from unusable parameters or data is a setting error
// (core/error.hpp: std::invalid_argument naming it; under -fno-exceptions, a message and abort);
// Viterbi and the forward filter refuse a bad observation with a Status and never throw.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "ctxfuse/core/error.hpp"
#include "ctxfuse/core/status.hpp"

namespace ctxfuse::classify {

/// log(sum(exp(v))) without overflow; -inf when every entry is -inf.
template <typename Derived>
double log_sum_exp(const Eigen::MatrixBase<Derived>& v) {
  const double peak = v.maxCoeff();
  if (!std::isfinite(peak)) return peak;  // all -inf (or a +inf/NaN that must propagate)
  return peak + std::log((v.array() - peak).exp().sum());
}

enum class CovarianceKind { full, diagonal };

template <int NumStates, int Dim>
struct GaussianHmm {
  static_assert(NumStates >= 1 && Dim >= 1, "GaussianHmm needs fixed positive sizes");
  static constexpr int num_states = NumStates;
  static constexpr int dim = Dim;
  using Observation = Eigen::Matrix<double, Dim, 1>;
  using Covariance = Eigen::Matrix<double, Dim, Dim>;
  using StateVector = Eigen::Matrix<double, NumStates, 1>;
  using TransitionMatrix = Eigen::Matrix<double, NumStates, NumStates>;

  StateVector log_initial = StateVector::Constant(-std::log(double(NumStates)));
  /// log_transition(i, j) = log P(state_t = j | state_{t-1} = i); rows are "from".
  TransitionMatrix log_transition = TransitionMatrix::Constant(-std::log(double(NumStates)));
  std::array<Observation, NumStates> means{};
  std::array<Covariance, NumStates> covariances{};
  // Derived from covariances by finalize(); kept so that an emission costs one triangular solve.
  std::array<Covariance, NumStates> cholesky_lower{};
  std::array<double, NumStates> log_normaliser{};

  /// Recomputes the Cholesky factors; throws std::invalid_argument naming the state whose
  /// covariance is not symmetric positive definite or whose parameters are not finite.
  void finalize() {
    for (int k = 0; k < NumStates; ++k) {
      if (!means[k].allFinite() || !covariances[k].allFinite())
        ctxfuse::detail::invalid_setting("GaussianHmm: state " + std::to_string(k) +
                                    " has a non-finite mean or covariance");
      Eigen::LLT<Covariance> llt(covariances[k]);
      if (llt.info() != Eigen::Success)
        ctxfuse::detail::invalid_setting("GaussianHmm: covariance of state " + std::to_string(k) +
                                    " is not positive definite");
      cholesky_lower[k] = llt.matrixL();
      const double log_det = 2.0 * cholesky_lower[k].diagonal().array().log().sum();
      log_normaliser[k] = -0.5 * (Dim * std::log(2.0 * std::numbers::pi) + log_det);
    }
    if (std::isnan(log_initial.sum()) || std::isnan(log_transition.sum()))
      ctxfuse::detail::invalid_setting("GaussianHmm: NaN in initial or transition log-probabilities");
  }

  double log_emission(int state, const Observation& x) const {
    const Observation whitened =
        cholesky_lower[state].template triangularView<Eigen::Lower>().solve(x - means[state]);
    return log_normaliser[state] - 0.5 * whitened.squaredNorm();
  }

  StateVector log_emissions(const Observation& x) const {
    StateVector out;
    for (int k = 0; k < NumStates; ++k) out[k] = log_emission(k, x);
    return out;
  }
};

/// Builds a model from linear-domain probabilities; rows of `transition` and `initial` must
/// sum to 1 within 1e-9 (throws std::invalid_argument otherwise).
template <int N, int D>
GaussianHmm<N, D> make_gaussian_hmm(const Eigen::Matrix<double, N, 1>& initial,
                                    const Eigen::Matrix<double, N, N>& transition,
                                    const std::array<Eigen::Matrix<double, D, 1>, N>& means,
                                    const std::array<Eigen::Matrix<double, D, D>, N>& covariances) {
  auto check_distribution = [](const auto& p, const std::string& what) {
    if (!p.allFinite() || (p.array() < 0.0).any() || std::abs(p.sum() - 1.0) > 1e-9)
      ctxfuse::detail::invalid_setting("make_gaussian_hmm: " + what +
                                  " is not a probability distribution (finite, >= 0, sums to 1)");
  };
  check_distribution(initial, "initial");
  for (int i = 0; i < N; ++i)
    check_distribution(transition.row(i), "transition row " + std::to_string(i));
  GaussianHmm<N, D> hmm;
  hmm.log_initial = initial.array().log().matrix();
  hmm.log_transition = transition.array().log().matrix();
  hmm.means = means;
  hmm.covariances = covariances;
  hmm.finalize();
  return hmm;
}

/// One labelled training sequence: observations[t] was emitted in region labels[t].
template <int D>
struct LabelledSequence {
  std::span<const Eigen::Matrix<double, D, 1>> observations;
  std::span<const int> labels;
};

struct HmmFitOptions {
  CovarianceKind covariance = CovarianceKind::full;
  /// Added to every transition and initial count (Laplace smoothing), so that a transition
  /// never seen in training is improbable rather than impossible. 0 gives the plain
  /// maximum-likelihood frequencies.
  double pseudo_count = 1.0;
  /// Added to each covariance diagonal; keeps a region with (near-)constant features usable.
  double variance_floor = 1e-6;
};

/// Supervised maximum-likelihood estimate of pi, A and the Gaussian emissions from labelled
/// sequences. pi counts the first label of each sequence, A the consecutive label pairs
/// within each sequence; emissions use the sample mean and the (1/n) sample covariance.
/// Throws std::invalid_argument on mismatched lengths, labels outside [0, N), non-finite
/// observations, or a state with fewer than 2 samples.
template <int N, int D>
GaussianHmm<N, D> fit_supervised(std::span<const LabelledSequence<D>> sequences,
                                 const HmmFitOptions& options = {}) {
  using Vec = Eigen::Matrix<double, D, 1>;
  using Mat = Eigen::Matrix<double, D, D>;
  if (!(options.pseudo_count >= 0.0) || !(options.variance_floor >= 0.0))
    ctxfuse::detail::invalid_setting("fit_supervised: pseudo_count and variance_floor must be >= 0");
  Eigen::Matrix<double, N, 1> initial_counts = Eigen::Matrix<double, N, 1>::Zero();
  Eigen::Matrix<double, N, N> transition_counts = Eigen::Matrix<double, N, N>::Zero();
  std::array<double, N> n{};
  std::array<Vec, N> sum;
  std::array<Mat, N> sum_outer;
  for (int k = 0; k < N; ++k) {
    sum[k].setZero();
    sum_outer[k].setZero();
  }
  for (std::size_t s = 0; s < sequences.size(); ++s) {
    const auto& seq = sequences[s];
    if (seq.observations.size() != seq.labels.size())
      ctxfuse::detail::invalid_setting("fit_supervised: sequence " + std::to_string(s) + " has " +
                                  std::to_string(seq.observations.size()) + " observations but " +
                                  std::to_string(seq.labels.size()) + " labels");
    for (std::size_t t = 0; t < seq.labels.size(); ++t) {
      const int k = seq.labels[t];
      if (k < 0 || k >= N)
        ctxfuse::detail::invalid_setting("fit_supervised: sequence " + std::to_string(s) + " epoch " +
                                    std::to_string(t) + ": label " + std::to_string(k) +
                                    " outside [0, " + std::to_string(N) + ")");
      const Vec& x = seq.observations[t];
      if (!x.allFinite())
        ctxfuse::detail::invalid_setting("fit_supervised: sequence " + std::to_string(s) + " epoch " +
                                    std::to_string(t) + ": non-finite observation");
      if (t == 0)
        initial_counts[k] += 1.0;
      else
        transition_counts(seq.labels[t - 1], k) += 1.0;
      n[k] += 1.0;
      sum[k] += x;
      sum_outer[k] += x * x.transpose();
    }
  }
  GaussianHmm<N, D> hmm;
  initial_counts.array() += options.pseudo_count;
  if (initial_counts.sum() <= 0.0)
    ctxfuse::detail::invalid_setting("fit_supervised: no sequences and pseudo_count 0");
  hmm.log_initial = (initial_counts / initial_counts.sum()).array().log().matrix();
  transition_counts.array() += options.pseudo_count;
  for (int i = 0; i < N; ++i) {
    const double row = transition_counts.row(i).sum();
    // A state never left (or never visited) keeps itself: the least surprising assumption.
    if (row <= 0.0) {
      hmm.log_transition.row(i).setConstant(-std::numeric_limits<double>::infinity());
      hmm.log_transition(i, i) = 0.0;
    } else {
      hmm.log_transition.row(i) = (transition_counts.row(i) / row).array().log().matrix();
    }
  }
  for (int k = 0; k < N; ++k) {
    if (n[k] < 2.0)
      ctxfuse::detail::invalid_setting("fit_supervised: state " + std::to_string(k) + " has " +
                                  std::to_string(int(n[k])) +
                                  " samples; at least 2 are needed for its covariance");
    hmm.means[k] = sum[k] / n[k];
    Mat cov = sum_outer[k] / n[k] - hmm.means[k] * hmm.means[k].transpose();
    cov = 0.5 * (cov + cov.transpose()).eval();
    if (options.covariance == CovarianceKind::diagonal) cov = Mat(cov.diagonal().asDiagonal());
    cov.diagonal().array() += options.variance_floor;
    hmm.covariances[k] = cov;
  }
  hmm.finalize();
  return hmm;
}

template <int N>
struct ViterbiResult {
  std::vector<int> path;
  double log_probability = -std::numeric_limits<double>::infinity();  // log p(path, observations)
  /// Accepted, or invalid input (Problem::non_finite_measurement) with the path empty and
  /// `refused_at` the index of the first non-finite observation.
  Status status{};
  std::size_t refused_at = 0;
};

/// Most probable state sequence of a batch (eq. 17). An empty batch gives an empty path; a
/// non-finite observation is refused (ViterbiResult::status) before any work is done.
template <int N, int D>
ViterbiResult<N> viterbi(const GaussianHmm<N, D>& hmm,
                         std::span<const Eigen::Matrix<double, D, 1>> observations) {
  using StateVector = Eigen::Matrix<double, N, 1>;
  ViterbiResult<N> result;
  const std::size_t T = observations.size();
  if (T == 0) return result;
  for (std::size_t t = 0; t < T; ++t)
    if (!observations[t].allFinite()) {
      result.status = Status::invalid(Problem::non_finite_measurement);
      result.refused_at = t;
      return result;
    }
  std::vector<std::array<int, N>> back(T);
  StateVector delta = StateVector::Constant(-std::numeric_limits<double>::infinity());
  for (std::size_t t = 0; t < T; ++t) {
    const StateVector emission = hmm.log_emissions(observations[t]);
    if (t == 0) {
      delta = hmm.log_initial + emission;
      back[0].fill(-1);
      continue;
    }
    StateVector next;
    for (int j = 0; j < N; ++j) {
      int best = 0;
      double best_score = -std::numeric_limits<double>::infinity();
      for (int i = 0; i < N; ++i) {
        const double score = delta[i] + hmm.log_transition(i, j);
        if (score > best_score) {  // strict: ties keep the lowest "from" index
          best_score = score;
          best = i;
        }
      }
      next[j] = best_score + emission[j];
      back[t][j] = best;
    }
    delta = next;
  }
  int state = 0;
  result.log_probability = delta.maxCoeff(&state);
  result.path.resize(T);
  for (std::size_t t = T; t-- > 0;) {
    result.path[t] = state;
    if (t > 0) state = back[t][state];
  }
  return result;
}

/// Online forward filter: after each step, posterior() = p(state_t | observations_1..t).
/// The state is a normalised log-posterior of fixed size, so a step never allocates.
template <int N, int D>
class HmmForwardFilter {
 public:
  using Model = GaussianHmm<N, D>;
  using StateVector = Eigen::Matrix<double, N, 1>;
  using Observation = typename Model::Observation;

  explicit HmmForwardFilter(const Model& model) : model_(&model) { reset(); }

  void reset() {
    log_posterior_ = model_->log_initial;
    log_likelihood_ = 0.0;
    steps_ = 0;
  }

  /// Folds in one observation: accepted, with Status::log_likelihood the step's evidence
  /// log p(x_t | x_1..t-1). Refused, the filter left unchanged: a non-finite observation
  /// (invalid input, Problem::non_finite_measurement) or one that no state can have emitted
  /// (numerical failure, Problem::zero_likelihood: the likelihood underflows to 0).
  Status step(const Observation& x) {
    if (!x.allFinite()) return Status::invalid(Problem::non_finite_measurement);
    StateVector predicted;
    if (steps_ == 0) {
      predicted = model_->log_initial;
    } else {
      for (int j = 0; j < N; ++j)
        predicted[j] = log_sum_exp(log_posterior_ + model_->log_transition.col(j));
    }
    const StateVector joint = predicted + model_->log_emissions(x);
    const double evidence = log_sum_exp(joint);
    if (!std::isfinite(evidence)) return Status::failure(Problem::zero_likelihood);
    log_posterior_ = joint.array() - evidence;
    log_likelihood_ += evidence;
    ++steps_;
    Status accepted;
    accepted.log_likelihood = evidence;
    return accepted;
  }

  StateVector posterior() const { return log_posterior_.array().exp().matrix(); }
  const StateVector& log_posterior() const { return log_posterior_; }
  int most_probable() const {
    int k = 0;
    log_posterior_.maxCoeff(&k);
    return k;
  }
  /// log p(observations_1..t) accumulated over the accepted steps.
  double log_likelihood() const { return log_likelihood_; }
  std::size_t steps() const { return steps_; }

 private:
  const Model* model_;
  StateVector log_posterior_;
  double log_likelihood_ = 0.0;
  std::size_t steps_ = 0;
};

}  // namespace ctxfuse::classify

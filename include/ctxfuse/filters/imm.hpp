// Interacting multiple model (IMM) estimator over a compile-time set of mode filters
// (Bar-Shalom, Li, Kirubarajan, "Estimation with Applications to Tracking and Navigation",
// ch. 11.6). Modes are held in a boost::hana::tuple and may differ in process model, process
// noise, gate and the measurements they take; they share the state type (a vector state, or
// an error-state nominal with the same retraction).
//
// One IMM cycle, as this class splits it so that a multi-rate system (IMU at 100 Hz, GNSS at
// 1 Hz, UWB at 10 Hz) can run it:
//   mix()                      c_j = sum_i p_ij mu_i, mu_{i|j} = p_ij mu_i / c_j, mixed
//                              means/covariances with the spread of means; opens the cycle.
//                              Refused (Problem::imm_cycle_not_closed, nothing changed) while
//                              the previous cycle is open: mixing again without the close would
//                              keep mu at its old value forever, silently.
//   predict(u, dt)  (any number of times) mode-matched prediction.
//   update(tag, meas, z, mask) (any number of times) mode-matched corrections; every mode is
//                              scored on the measurement (see "Routing") and the log-likelihoods
//                              of the cycle accumulate per mode.
//   update_mode_probabilities() mu_j ∝ Lambda_j c_j in the log domain, floor, closes the cycle.
//   combined()                 x = sum mu_j x_j, P = sum mu_j (P_j + spread); while a cycle
//                              is open the weights are ImmOptions::prior_weights' (the textbook
//                              c_j or the last closed cycle's mu_j: see PriorWeights).
// cycle(u, dt, observe(tag, meas, z, mask)...) runs the common cycle (mix, one predict, the
// updates in order, the close) in one call; the split steps stay for multi-rate systems.
// mixing_weights() and predicted_probabilities() read the last mix()'s mu_{i|j} and c_j.
// The transition matrix comes from a MixingPolicy (policies/mixing.hpp), asked once per mix():
// its entries are per cycle, not per second, so a caller that mixes at every measurement epoch
// chooses p_ij for that epoch spacing.
//
// Routing. A measurement carries a tag type. Mode j takes it when its Accepts<> list contains
// the tag (compile time) AND bit j of the runtime mask is set (e.g. from the recognised
// region). A mode that takes it is corrected with it; a mode that does not is still scored
// on it (innovation likelihood of its prediction, no correction), because comparing modes
// by likelihoods of different measurement sets would favour whichever mode looks at less
// data -- a dead-reckoning mode that skips every measurement would never lose.
//
// Likelihoods stay in the log domain (log-sum-exp), so a far outlier whose likelihood
// underflows to zero in every mode cannot zero every mode probability.
// Partial rejection: when at least one taker accepts, every mode's log-likelihood enters,
// including those of takers whose gate rejected it (the core reports it for gated updates):
// a mode that finds the measurement implausible should lose probability.
// Total rejection: when no mode that takes a measurement accepts it (all gated, invalid or
// numerically failed), the measurement contributes to no mode's likelihood: the mode
// probabilities of the cycle are then those of the prediction, c_j, as far as that
// measurement is concerned. A measurement that no mode takes (mask empty) is ignored.
// Floor: after the update every mu_j is raised to at least `probability_floor` and the vector
// renormalised, so that a mode can come back after a long run of bad luck.
//
// Error-state modes (nominal with quaternion, etc.): mixing and combination happen in the
// error space around a reference nominal, the one of the most probable mode:
// dx_i = difference(x_i, ref), mixed dx_0j = sum mu_{i|j} dx_i, x_0j = inject(ref, dx_0j),
// P_0j = sum mu_{i|j} (P_i + (dx_i - dx_0j)(dx_i - dx_0j)'). P_i is used as it is, i.e. the
// error covariance is not transported from x_i's tangent space to ref's; the modes' nominals
// stay close (they are mixed every cycle), so the transport (identity to first order in the
// attitude difference) is neglected. For vector states difference/inject are -/+ (or the
// model's own, e.g. with an angle wrapped, when it defines them) and all of this is the
// textbook formula exactly (the reference cancels).
//
// No step allocates: beliefs are fixed-size and live inside the object.
// Also read: imm_modes.hpp (Mode, Accepts, belief storage), imm_types.hpp (ImmOptions and
// PriorWeights, UpdateResult, CycleResult, observe), imm_moments.hpp (the weighted sums).
#pragma once

#include <boost/hana.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <tuple>
#include <type_traits>

#include "ctxfuse/core/concepts.hpp"
#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/core/retraction.hpp"
#include "ctxfuse/core/validation.hpp"
#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/filters/imm_modes.hpp"
#include "ctxfuse/filters/imm_moments.hpp"
#include "ctxfuse/filters/imm_types.hpp"
#include "ctxfuse/policies/gating.hpp"

namespace ctxfuse::imm {

namespace hana = boost::hana;

template <class Mixing, class... Modes>
class Imm {
 public:
  static constexpr int R = static_cast<int>(sizeof...(Modes));
  static_assert(R >= 1, "an IMM needs at least one mode");
  using FirstModel = typename std::tuple_element_t<0, std::tuple<Modes...>>::ProcessModelType;
  using State = typename FirstModel::State;
  using Input = typename FirstModel::Input;
  static constexpr int N = FirstModel::dim;
  static_assert(((std::is_same_v<typename Modes::ProcessModelType::State, State> &&
                  std::is_same_v<typename Modes::ProcessModelType::Input, Input> &&
                  Modes::ProcessModelType::dim == N) && ...),
                "every IMM mode must share the state type, the input type and the dimension");
  using Belief = detail::BeliefOf<FirstModel>;
  using Probabilities = Vector<R>;
  using TransitionMatrix = SquareMatrix<R>;

  /// All modes start from `initial` with probabilities `mu0` (normalised here).
  Imm(Mixing mixing, hana::tuple<Modes...> modes, const Belief& initial, const Probabilities& mu0,
      ImmOptions<R> options = {})
      : mixing_(std::move(mixing)), modes_(std::move(modes)), options_(options) {
    hana::for_each(indices(), [&](auto j) { buffers_[0][j] = initial; });
    mu_ = mu0.cwiseMax(0.0);
    const double s = mu_.sum();
    mu_ = s > 0.0 ? Probabilities(mu_ / s) : Probabilities::Constant(1.0 / R);
    c_ = mu_;
    w_.setIdentity();  // no mixing yet: every mode is its own
    log_lik_.setZero();
  }

  const Probabilities& mode_probabilities() const { return mu_; }
  /// c_j of the open cycle (predicted mode probabilities); mu_j once the cycle is closed.
  const Probabilities& predicted_probabilities() const { return c_; }
  /// The last mix()'s mixing weights: entry (i, j) is mu_{i|j} = p_ij mu_i / c_j, the share of
  /// mode i in mode j's mixed prior, so every column sums to 1. Identity before the first mix().
  const TransitionMatrix& mixing_weights() const { return w_; }
  /// Whether mix() has opened a cycle that update_mode_probabilities() has not closed yet.
  bool cycle_open() const { return cycle_open_; }
  /// The weights combined() uses now: c_j or mu_j while a cycle is open (ImmOptions::
  /// prior_weights), mu_j once it is closed (then c_j = mu_j).
  const Probabilities& combination_weights() const {
    return options_.prior_weights == PriorWeights::predicted ? c_ : mu_;
  }
  /// Accumulated log-likelihood per mode in the open cycle.
  const Probabilities& cycle_log_likelihood() const { return log_lik_; }
  /// Mode J's belief. The reference refers to one of two buffers that the steps alternate
  /// between: read it again after mix(), predict() or update() rather than keeping it.
  template <int J>
  const auto& mode_belief() const { return belief(hana::size_c<J>); }
  template <int J>
  auto& mode_belief() { return belief(hana::size_c<J>); }
  template <int J>
  const auto& mode() const { return modes_[hana::size_c<J>]; }
  Mixing& mixing() { return mixing_; }
  const Mixing& mixing() const { return mixing_; }
  const ImmOptions<R>& options() const { return options_; }
  int most_probable() const {
    int best = 0;
    for (int j = 1; j < R; ++j)
      if (mu_(j) > mu_(best)) best = j;
    return best;
  }

  /// Interaction/mixing step with the policy's current transition matrix; opens a cycle.
  /// Refused, changing nothing: while the previous cycle is open (imm_cycle_not_closed), when
  /// the matrix is not row-stochastic (transition_matrix_not_stochastic, invalid input) or when
  /// c_j is not finite or zero for every j (mode_probabilities_vanished, numerical failure).
  Status mix() {
    if (cycle_open_) return Status::invalid(Problem::imm_cycle_not_closed);
    const TransitionMatrix P = mixing_.matrix();
    if (!is_row_stochastic(P)) return Status::invalid(Problem::transition_matrix_not_stochastic);
    const Probabilities c = P.transpose() * mu_;
    if (!c.allFinite() || !(c.sum() > 0.0)) return Status::failure(Problem::mode_probabilities_vanished);
    detail::mixing_weights<R>(P, mu_, c, w_);

    const Spread spread = spread_around_most_probable();
    // The mixed beliefs need every P_i, so they are built in the spare buffers (lower
    // triangles, one pass each) and the buffers are swapped once all are done.
    hana::for_each(indices(), [&](auto j) { match_into(model_of(j), spread, w_.col(decltype(j)::value), spare(j)); });
    for (auto& b : current_) b ^= 1u;
    c_ = c;
    log_lik_.setZero();
    cycle_open_ = true;
    return Status{};
  }

  /// Mode-matched prediction of every mode. All or nothing: if any mode rejects the step the
  /// status of the first rejecting mode is returned and no mode changes.
  Status predict(const Input& u, double dt) {
    // The predicted beliefs go to the spare buffers, committed together by swapping buffers:
    // error-state modes predict straight into them; vector-state modes copy their prior first.
    Status first{};
    bool ok = true;
    hana::for_each(indices(), [&](auto j) {
      if (!ok) return;
      Status s;
      if constexpr (detail::is_error_state<ModelAt<decltype(j)::value>>) {
        s = eskf::detail::predict_into(model_of(j), belief(j), spare(j), u, dt, options_.filter, nullptr);
      } else {
        spare(j) = belief(j);
        s = ekf::predict(model_of(j), spare(j), u, dt, options_.filter);
      }
      if (!s.accepted()) {
        ok = false;
        first = s;
      }
    });
    if (ok)
      for (auto& b : current_) b ^= 1u;
    return first;
  }

  /// Mode-matched correction with one measurement. `meas` is either one measurement model for
  /// every mode or a hana::tuple with one model per mode (e.g. a sensor weighted differently
  /// in one mode). `mask` bit j lets mode j take the tag (default: all). Invalid input
  /// (NaN, absurd magnitude, bad noise) changes nothing and is reported in `problem`.
  template <class Tag, class Meas, int M>
  UpdateResult<R> update(Tag, const Meas& meas, const Vector<M>& z, std::uint32_t mask = ~std::uint32_t{0}) {
    UpdateResult<R> result;
    Probabilities ll = Probabilities::Zero();
    std::array<bool, R> scored_ok{};
    hana::for_each(indices(), [&](auto j) {
      constexpr int jj = decltype(j)::value;
      using ModeT = std::remove_cvref_t<decltype(modes_[j])>;
      const auto& mj = measurement_for(meas, j);
      using MeasT = std::remove_cvref_t<decltype(mj)>;
      static_assert(MeasT::dim == M, "measurement dimension does not match z");
      const bool takes = ModeT::TakenTags::template contains<Tag> && ((mask >> jj) & 1u);
      result.taken[jj] = takes;
      Status s;
      if (takes) {
        if constexpr (detail::is_error_state<ModelAt<decltype(j)::value>>) {
          // Corrected into the spare buffer, which becomes the mode's belief on acceptance.
          s = eskf::detail::update_into(model_of(j), mj, belief(j), spare(j), z, modes_[j].gate, options_.filter,
                                        nullptr);
          if (s.accepted()) current_[jj] ^= 1u;
        } else {
          s = ekf::update<N>(mj, belief(j), z, modes_[j].gate, options_.filter);
        }
        ++result.taken_count;
        if (s.accepted()) ++result.accepted_count;
      } else {
        s = detail::score_prediction<N>(mj, belief(j), z, options_.filter);
      }
      result.mode[jj] = s;
      if (s.outcome == Outcome::invalid_input && result.problem == Problem::none) result.problem = s.problem;
      scored_ok[jj] = std::isfinite(s.log_likelihood);
      ll(jj) = s.log_likelihood;
    });
    if (result.accepted_count == 0) return result;  // total rejection or nothing taken
    // Modes whose likelihood could not be computed (e.g. innovation covariance not positive
    // definite) get the worst finite score of the others rather than a NaN.
    double worst = std::numeric_limits<double>::infinity();
    for (int j = 0; j < R; ++j)
      if (scored_ok[j]) worst = std::min(worst, ll(j));
    for (int j = 0; j < R; ++j)
      if (!scored_ok[j]) ll(j) = worst;
    log_lik_ += ll;
    result.scored = true;
    return result;
  }

  /// mu_j ∝ exp(L_j) c_j with L_j the log-likelihood accumulated since mix(); closes the cycle.
  /// Without an open cycle it changes nothing but the floor (c_j = mu_j and no likelihood).
  void update_mode_probabilities() {
    Probabilities log_post;
    for (int j = 0; j < R; ++j) log_post(j) = (c_(j) > 0.0 ? std::log(c_(j)) : -std::numeric_limits<double>::infinity()) + log_lik_(j);
    const double top = log_post.maxCoeff();
    Probabilities mu = c_;
    if (std::isfinite(top)) {
      mu = (log_post.array() - top).exp().matrix();
      mu /= mu.sum();
    }
    detail::apply_floor<R>(mu, options_.probability_floor);
    mu_ = mu;
    c_ = mu_;
    log_lik_.setZero();
    cycle_open_ = false;
  }

  /// The common cycle in one call: mix(), predict(u, dt), update() with each observation in
  /// order (make them with imm::observe), update_mode_probabilities(). A refused mix() stops
  /// the cycle with nothing changed. A refused predict() skips the updates (they would correct
  /// beliefs that are not at the measurements' time) but still closes the cycle, with no
  /// likelihood: mu_j = c_j, the probabilities of the mixed beliefs the modes now hold.
  template <class... Obs>
  CycleResult<R, sizeof...(Obs)> cycle(const Input& u, double dt, const Obs&... obs) {
    CycleResult<R, sizeof...(Obs)> out;
    out.mix = mix();
    if (!out.mix.accepted()) return out;
    out.predict = predict(u, dt);
    if (out.predict.accepted()) {
      std::size_t k = 0;
      ((out.updates[k++] = update(typename Obs::TagType{}, obs.model, obs.z, obs.mask)), ...);
    }
    update_mode_probabilities();
    return out;
  }

  /// Moment-matched combination of the mode estimates (around the most probable mode's point
  /// for error-state modes), weighted with combination_weights().
  Belief combined() const { return combined_with(combination_weights()); }
  /// The same with the weights named here rather than in the options (e.g. both priors side by
  /// side); the same belief for both once the cycle is closed.
  Belief combined(PriorWeights weights) const { return combined_with(weights == PriorWeights::predicted ? c_ : mu_); }

  /// Replaces the mode probabilities (normalised, floored) without touching the estimates. An
  /// open cycle stays open: its likelihoods so far will weigh these probabilities at the close.
  void set_mode_probabilities(const Probabilities& mu) {
    Probabilities p = mu.cwiseMax(0.0);
    const double s = p.sum();
    p = s > 0.0 ? Probabilities(p / s) : Probabilities::Constant(1.0 / R);
    detail::apply_floor<R>(p, options_.probability_floor);
    mu_ = p;
    c_ = p;
  }

  static bool is_row_stochastic(const TransitionMatrix& P, double tol = 1e-9) { return detail::row_stochastic<R>(P, tol); }

 private:
  template <std::size_t J>
  using ModelAt = std::tuple_element_t<J, std::tuple<typename Modes::ProcessModelType...>>;

  static constexpr auto indices() { return hana::make_range(hana::size_c<0>, hana::size_c<R>); }

  Belief combined_with(const Probabilities& weights) const {
    Belief out;
    match_into(modes_[hana::size_c<0>].model, spread_around_most_probable(), weights, out);
    return out;
  }

  /// The mode estimates as differences from the most probable mode's point (error-state modes
  /// mix in that mode's tangent space), with their covariances: what every moment match reads.
  struct Spread {
    State ref_point;
    Matrix<N, R> dx;
    std::array<const SquareMatrix<N>*, R> covs;
  };
  Spread spread_around_most_probable() const {
    Spread sp;
    sp.ref_point = point_of(most_probable());
    hana::for_each(indices(), [&](auto i) {
      sp.dx.col(decltype(i)::value) = state_difference(model_of(i), detail::point(belief(i)), sp.ref_point);
      sp.covs[i] = &belief(i).cov;
    });
    return sp;
  }

  /// The moment-matched belief of the modes under `weights` (a column of the mixing weights,
  /// or the mode probabilities), written into `out`.
  template <class Model, class WeightExpr>
  static void match_into(const Model& model, const Spread& sp, const WeightExpr& weights, Belief& out) {
    const Vector<N> mean_dx = sp.dx.lazyProduct(weights);
    detail::moment_match_lower<N, R>(sp.covs, sp.dx, mean_dx, weights, out.cov);
    symmetrize(out.cov);
    detail::point(out) = state_inject(model, sp.ref_point, mean_dx);
  }

  template <class J>
  auto& belief(J j) {
    return buffers_[current_[J::value]][j];
  }
  template <class J>
  const auto& belief(J j) const {
    return buffers_[current_[J::value]][j];
  }
  template <class J>
  auto& spare(J j) {
    return buffers_[current_[J::value] ^ 1u][j];
  }

  template <class J>
  const auto& model_of(J j) const {
    return modes_[j].model;
  }

  State point_of(int index) const {
    State out{};
    hana::for_each(indices(), [&](auto i) {
      if (decltype(i)::value == index) out = detail::point(belief(i));
    });
    return out;
  }

  template <class Meas, class J>
  static const auto& measurement_for(const Meas& meas, J j) {
    if constexpr (detail::is_hana_tuple<Meas>()) {
      static_assert(decltype(hana::size(meas))::value == R, "one measurement model per mode");
      return meas[j];
    } else {
      (void)j;
      return meas;
    }
  }

  Mixing mixing_;
  hana::tuple<Modes...> modes_;
  // Two belief buffers per mode; current_[j] says which one holds mode j's belief. A step
  // writes the other one and commits by flipping the index: no covariance is copied.
  std::array<hana::tuple<detail::BeliefOf<typename Modes::ProcessModelType>...>, 2> buffers_;
  std::array<unsigned char, R> current_{};
  Probabilities mu_;
  Probabilities c_;
  TransitionMatrix w_;  // mixing weights of the last mix(), column j = mu_{i|j}
  Probabilities log_lik_;
  ImmOptions<R> options_;
  bool cycle_open_ = false;  // set by mix(), cleared by update_mode_probabilities()
};

}  // namespace ctxfuse::imm

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
//   predict(u, dt)  (any number of times) mode-matched prediction.
//   update(tag, meas, z, mask) (any number of times) mode-matched corrections; every mode is
//                              scored on the measurement (see "Routing") and the log-likelihoods
//                              of the cycle accumulate per mode.
//   update_mode_probabilities() mu_j ∝ Lambda_j c_j in the log domain, floor, closes the cycle.
//   combined()                 x = sum mu_j x_j, P = sum mu_j (P_j + spread).
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
#include "ctxfuse/policies/gating.hpp"

namespace ctxfuse::imm {

namespace hana = boost::hana;

/// Measurement tags a mode takes; `AcceptsAll` takes every tag.
template <class... Tags>
struct Accepts {
  template <class Tag>
  static constexpr bool contains = (std::is_same_v<Tag, Tags> || ...);
};
struct AcceptsAll {
  template <class Tag>
  static constexpr bool contains = true;
};

/// One mode of the IMM: a process model (its own process noise), the tags it takes, a gate.
template <ProcessModel Model, class Taken = AcceptsAll, GatePolicy Gate = NoGate>
struct Mode {
  using ProcessModelType = Model;
  using TakenTags = Taken;
  using GateType = Gate;
  Model model{};
  Gate gate{};
};

template <class Model, class Taken = AcceptsAll, class Gate = NoGate>
Mode<Model, Taken, Gate> make_mode(Model model, Taken = {}, Gate gate = {}) {
  return {std::move(model), std::move(gate)};
}

namespace detail {

template <class Model>
inline constexpr bool is_error_state = ErrorStateProcessModel<Model> && !VectorProcessModel<Model>;

/// Belief storage of a mode: Gaussian for vector states, nominal + error covariance otherwise.
template <class Model, bool ErrorState = is_error_state<Model>>
struct BeliefSelect {
  using type = Gaussian<Model::dim>;
};
template <class Model>
struct BeliefSelect<Model, true> {
  using type = ErrorStateBelief<typename Model::State, Model::dim>;
};
template <class Model>
using BeliefOf = typename BeliefSelect<Model>::type;

template <class B>
auto& point(B& b) {
  if constexpr (requires { b.nominal; })
    return b.nominal;
  else
    return b.mean;
}

template <class T>
constexpr bool is_hana_tuple() {
  return hana::is_a<hana::tuple_tag, T>;
}

}  // namespace detail

/// What one IMM update did, per mode and overall.
template <int R>
struct UpdateResult {
  std::array<Status, R> mode{};   // status of each mode's correction (or scoring, when not taken)
  std::array<bool, R> taken{};    // whether the mode took (was offered) the measurement
  int taken_count = 0;
  int accepted_count = 0;         // modes that took it and were corrected
  bool scored = false;            // the likelihoods entered the mode probabilities
  Problem problem = Problem::none;  // invalid input common to all modes, if any

  bool any_accepted() const { return accepted_count > 0; }
};

template <int R>
struct ImmOptions {
  double probability_floor = 1e-6;  // each mu_j is kept >= this (then renormalised)
  FilterOptions filter{};
};

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
    log_lik_.setZero();
  }

  const Probabilities& mode_probabilities() const { return mu_; }
  /// c_j of the open cycle (predicted mode probabilities).
  const Probabilities& predicted_probabilities() const { return c_; }
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

  /// Interaction/mixing step with the policy's current transition matrix. Returns false (and
  /// changes nothing) when the matrix is not row-stochastic or c_j vanishes for every j.
  bool mix() {
    const TransitionMatrix P = mixing_.matrix();
    if (!is_row_stochastic(P)) return false;
    const Probabilities c = P.transpose() * mu_;
    if (!c.allFinite() || !(c.sum() > 0.0)) return false;
    // mixing weights mu_{i|j}: column j
    TransitionMatrix w;
    for (int j = 0; j < R; ++j)
      for (int i = 0; i < R; ++i) w(i, j) = c(j) > 0.0 ? P(i, j) * mu_(i) / c(j) : (i == j ? 1.0 : 0.0);

    const Spread spread = spread_around_most_probable();
    // The mixed beliefs need every P_i, so they are built in the spare buffers (lower
    // triangles, one pass each) and the buffers are swapped once all are done.
    hana::for_each(indices(), [&](auto j) { match_into(model_of(j), spread, w.col(decltype(j)::value), spare(j)); });
    for (auto& b : current_) b ^= 1u;
    c_ = c;
    log_lik_.setZero();
    return true;
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
        s = score(mj, belief(j), z);
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
  void update_mode_probabilities() {
    Probabilities log_post;
    for (int j = 0; j < R; ++j) log_post(j) = (c_(j) > 0.0 ? std::log(c_(j)) : -std::numeric_limits<double>::infinity()) + log_lik_(j);
    const double top = log_post.maxCoeff();
    Probabilities mu = c_;
    if (std::isfinite(top)) {
      mu = (log_post.array() - top).exp().matrix();
      mu /= mu.sum();
    }
    apply_floor(mu);
    mu_ = mu;
    c_ = mu_;
    log_lik_.setZero();
  }

  /// Moment-matched combination of the mode estimates (around the most probable mode's point
  /// for error-state modes).
  Belief combined() const {
    Belief out;
    match_into(modes_[hana::size_c<0>].model, spread_around_most_probable(), mu_, out);
    return out;
  }

  /// Replaces the mode probabilities (normalised, floored) without touching the estimates.
  void set_mode_probabilities(const Probabilities& mu) {
    Probabilities p = mu.cwiseMax(0.0);
    const double s = p.sum();
    p = s > 0.0 ? Probabilities(p / s) : Probabilities::Constant(1.0 / R);
    apply_floor(p);
    mu_ = p;
    c_ = p;
  }

  static bool is_row_stochastic(const TransitionMatrix& P, double tol = 1e-9) {
    if (!P.allFinite() || (P.array() < 0.0).any()) return false;
    for (int i = 0; i < R; ++i)
      if (std::abs(P.row(i).sum() - 1.0) > tol) return false;
    return true;
  }

 private:
  template <std::size_t J>
  using ModelAt = std::tuple_element_t<J, std::tuple<typename Modes::ProcessModelType...>>;

  static constexpr auto indices() { return hana::make_range(hana::size_c<0>, hana::size_c<R>); }

  // Lower triangle of sum_i w_i (P_i + d_i d_i') with d_i = dx_i - m, in one pass per column:
  // the weighted covariances and the rank-R spread of the means together, accumulated in
  // registers (the textbook sum, without a pass over the whole matrix per term).
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
    moment_match_lower(sp.covs, sp.dx, mean_dx, weights, out.cov);
    symmetrize(out.cov);
    detail::point(out) = state_inject(model, sp.ref_point, mean_dx);
  }

  template <class MeanExpr, class WeightExpr>
  static void moment_match_lower(const std::array<const SquareMatrix<N>*, R>& covs, const Matrix<N, R>& dx,
                                 const MeanExpr& m, const WeightExpr& w, SquareMatrix<N>& out) {
    Matrix<N, R> d = dx.colwise() - Vector<N>(m);
    Matrix<N, R> dw = d * Vector<R>(w).asDiagonal();
    double wi[R];
    for (int i = 0; i < R; ++i) wi[i] = w(i);
    for (int c = 0; c < N; ++c) {
      double dc[R];
      const double* pc[R];
      for (int i = 0; i < R; ++i) {
        dc[i] = d(c, i);
        pc[i] = covs[static_cast<std::size_t>(i)]->data() + c * N;
      }
      const double* dwd = dw.data();
      double* o = out.data() + c * N;
      // Two rows at a time, sums in registers (one SIMD pair per step).
      int r = c;
      for (; r + 1 < N; r += 2) {
        double s0 = 0.0, s1 = 0.0;
        for (int i = 0; i < R; ++i) {
          s0 += wi[i] * pc[i][r] + dwd[i * N + r] * dc[i];
          s1 += wi[i] * pc[i][r + 1] + dwd[i * N + r + 1] * dc[i];
        }
        o[r] = s0;
        o[r + 1] = s1;
      }
      if (r < N) {
        double s0 = 0.0;
        for (int i = 0; i < R; ++i) s0 += wi[i] * pc[i][r] + dwd[i * N + r] * dc[i];
        o[r] = s0;
      }
    }
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

  // Innovation log-likelihood of the mode's prediction, without correcting it.
  template <class Meas, class B, int M>
  Status score(const Meas& meas, const B& belief, const Vector<M>& z) const {
    const SquareMatrix<M> Rm = meas.noise(belief_point(belief));
    if (Problem p = check_measurement<M>(z, Rm, options_.filter); p != Problem::none) return Status::invalid(p);
    if (Problem p = ctxfuse::detail::model_check(meas, z); p != Problem::none) return Status::invalid(p);
    Matrix<M, N> H;
    const Vector<M> zp = meas.predict(belief_point(belief), &H);
    const Vector<M> y = ctxfuse::detail::innovation(meas, z, zp);
    if (!H.allFinite() || !y.allFinite()) return Status::failure(Problem::non_finite_prediction);
    SquareMatrix<M> S = H * belief.cov * H.transpose();
    S += Rm;
    symmetrize(S);
    const InnovationSolve<M> solve(S);
    if (!solve.ok) return Status::failure(Problem::innovation_not_positive_definite);
    Status s;
    s.outcome = Outcome::gated;  // scored, not applied
    s.dof = M;
    s.nis = solve.nis(y);
    s.log_likelihood = solve.log_likelihood(s.nis);
    return s;
  }

  template <class B>
  static const State& belief_point(const B& b) {
    if constexpr (requires { b.nominal; })
      return b.nominal;
    else
      return b.mean;
  }

  void apply_floor(Probabilities& mu) const {
    const double floor = options_.probability_floor;
    if (!(floor > 0.0) || floor * R >= 1.0) return;
    // Raise the small ones to the floor and take the mass proportionally from the others, so
    // that the floored entries stay exactly at the floor after renormalisation.
    double fixed = 0.0, free = 0.0;
    for (int j = 0; j < R; ++j) (mu(j) < floor ? fixed : free) += (mu(j) < floor ? floor : mu(j));
    if (!(free > 0.0)) return;
    const double scale = (1.0 - fixed) / free;
    for (int j = 0; j < R; ++j) mu(j) = mu(j) < floor ? floor : mu(j) * scale;
  }

  Mixing mixing_;
  hana::tuple<Modes...> modes_;
  // Two belief buffers per mode; current_[j] says which one holds mode j's belief. A step
  // writes the other one and commits by flipping the index: no covariance is copied.
  std::array<hana::tuple<detail::BeliefOf<typename Modes::ProcessModelType>...>, 2> buffers_;
  std::array<unsigned char, R> current_{};
  Probabilities mu_;
  Probabilities c_;
  Probabilities log_lik_;
  ImmOptions<R> options_;
};

}  // namespace ctxfuse::imm

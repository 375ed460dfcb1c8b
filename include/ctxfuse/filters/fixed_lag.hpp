// Fixed-lag smoother: the last K states of a vector-state motion model, with the factors
// between them (motion between consecutive states, up to C measurements per state), solved
// jointly at every step by Gauss-Newton on the block-tridiagonal normal equations
// (core/block_tridiagonal.hpp), falling back to Levenberg-Marquardt damping when a step
// raises the cost. Older states are marginalised into a Gaussian prior on the oldest kept
// state, so the cost per step is bounded by K, not by the length of the run.
//
// Why a smoother rather than the EKF: the ranges of a whole window relinearise together
// (the EKF linearises each once, at its prior), and a state K-1 epochs back is estimated
// from the measurements after it too. With linear models the newest state equals the Kalman
// filter's estimate exactly; with ranges it matches it closely and the lagged states are
// better (tests/factors/fixed_lag_test.cpp measures both). The price is K states per solve.
//
// API (the whole of it):
//   FixedLagSmoother<Motion, Meas, K, C> s(motion, options);
//   Status s.initialise(t0, Gaussian prior [, Measurements at t0]);
//   Status s.step(t, u, measurements);     // u: the motion input over (t_prev, t]
//   s.newest(), s.newest_covariance(), s.newest_belief(), s.time(), s.report(), s.window()
// Measurements: fixed slots of (model, z, attached); a slot left unattached (an NLOS
// decision made outside, as a mask) stays out of the graph. An epoch with none attached is
// fine: the motion factor alone keeps the system positive definite.
//
// Every step either commits (accepted) or leaves the window exactly as it was and says why:
// invalid input (non-finite or out-of-order time, dt <= 0, bad input, bad measurement or
// noise), a non-positive-definite system, or no convergence in max_iterations. A step works
// on the second of two window buffers and swaps on success, so nothing is half-applied.
// Nothing is allocated on the heap after construction; the object holds both windows and two
// normal-equation systems by value (sizeof grows as K (C + dim^2)), so keep it as a member
// or on the heap rather than on a small stack.
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <type_traits>

#include "ctxfuse/core/block_tridiagonal.hpp"
#include "ctxfuse/core/factor.hpp"
#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/filters/factors.hpp"

namespace ctxfuse {

struct FixedLagOptions {
  int max_iterations = 20;
  /// Converged when no element of the Gauss-Newton step exceeds this (state units: metres,
  /// m/s). Gauss-Newton converges about quadratically on range problems (small residuals),
  /// so the error left after a step of 1e-6 is orders below it: the windows of
  /// tests/factors/ceres_equality_test.cpp agree with Ceres' solution to 1e-8 (it prints the
  /// gaps), in 3 iterations per step (bench/fixed_lag reports the count). A tighter value
  /// buys iterations that only move rounding.
  double step_tolerance = 1e-6;
  /// Undamped Gauss-Newton first; a step that raises the cost is taken back and the damping
  /// set to max(10 lambda, this) (Levenberg-Marquardt), divided by 10 after each step that
  /// lowers it. With levenberg_marquardt false every step is taken (plain Gauss-Newton).
  double min_lambda = 1e-6;
  bool levenberg_marquardt = true;
  FilterOptions limits{};
};

struct FixedLagReport {
  int iterations = 0;
  double initial_cost = std::numeric_limits<double>::quiet_NaN();  // 1/2 |r|^2 at the prediction
  double final_cost = std::numeric_limits<double>::quiet_NaN();
};

/// Up to C measurements of one epoch, each with its own model (an anchor and its sigma).
template <class Meas, int C>
struct EpochMeasurements {
  static constexpr int capacity = C;
  std::array<Meas, C> models{};
  std::array<Vector<Meas::dim>, C> z{};
  std::array<bool, C> attached{};
  int count = 0;

  /// False (nothing added) when all C slots are in use.
  bool add(const Meas& model, const Vector<Meas::dim>& value, bool attach = true) {
    if (count >= C) return false;
    const auto k = static_cast<std::size_t>(count++);
    models[k] = model;
    z[k] = value;
    attached[k] = attach;
    return true;
  }
  /// A value whose size is known only at run time would be read past its end when too short:
  /// convert it with a size check first (core/validation.hpp, copy_sized).
  template <DynamicSizeEigen Z>
  bool add(const Meas& model, const Z& value, bool attach = true) = delete;
  int attached_count() const {
    int n = 0;
    for (int i = 0; i < count; ++i) n += attached[static_cast<std::size_t>(i)] ? 1 : 0;
    return n;
  }
};

template <VectorProcessModel Motion, class Meas, int K, int C>
  requires MeasurementModel<Meas, Vector<Motion::dim>, Motion::dim>
class FixedLagSmoother {
 public:
  static_assert(K >= 2, "a window keeps at least two states");
  static constexpr int dim = Motion::dim;
  static constexpr int lag = K;
  using State = Vector<dim>;
  using Input = typename Motion::Input;
  using Measurements = EpochMeasurements<Meas, C>;

  /// An affine motion model's factor has constant Jacobians: their J'J blocks are formed once,
  /// when the factor is made, instead of at every linearisation of the window (K - 1 factors,
  /// about four linearisations per step).
  static constexpr bool affine_motion = AffineProcessModel<Motion>;
  /// Otherwise, a model that subtracts plainly keeps its factor's information W'W, formed
  /// once (WhitenedInformation): two products per linearisation instead of four.
  static constexpr bool plain_motion =
      !affine_motion && requires(const MotionFactor<Motion>& f, const State& a, SquareMatrix<dim>* J) { f.unwhitened(a, a, J); };
  struct NoMotionBlocks {};
  using MotionBlocks = std::conditional_t<affine_motion, AffineFactorBlocks<dim>,
                                          std::conditional_t<plain_motion, WhitenedInformation<dim>, NoMotionBlocks>>;

  struct Epoch {
    double time = 0.0;
    State x = State::Zero();
    MotionFactor<Motion> motion{};  // from the previous epoch; unused in the oldest slot
    [[no_unique_address]] MotionBlocks motion_blocks{};
    std::array<MeasurementFactor<dim, Meas>, C> factors{};
    int factor_count = 0;           // attached measurements, compacted to the front
  };
  /// epochs[0] is the oldest kept state, carrying `prior` (the marginalised past).
  struct Window {
    std::array<Epoch, K> epochs{};
    int size = 0;
    PriorFactor<dim> prior{};
    SquareMatrix<dim> newest_cov = SquareMatrix<dim>::Identity();
  };

  explicit FixedLagSmoother(Motion motion = {}, FixedLagOptions opts = {}) : motion_(motion), opts_(opts) {}

  bool initialised() const { return current().size > 0; }
  const Window& window() const { return current(); }
  const State& newest() const { return current().epochs[last()].x; }
  /// Marginal covariance of the newest state (the last Schur complement of the solve).
  const SquareMatrix<dim>& newest_covariance() const { return current().newest_cov; }
  Gaussian<dim> newest_belief() const { return Gaussian<dim>{newest(), newest_covariance()}; }
  double time() const { return current().epochs[last()].time; }
  const FixedLagReport& report() const { return report_; }
  const Motion& motion() const { return motion_; }
  const FixedLagOptions& options() const { return opts_; }

  /// Starts (or restarts) the window with one state, its prior and optional measurements.
  Status initialise(double t, const Gaussian<dim>& prior, const Measurements& meas = {}) {
    if (!std::isfinite(t)) return Status::invalid(Problem::non_finite_dt);
    Window& next = spare();
    PriorFactor<dim> p;
    if (Status s = make_prior_factor(prior, p); !s) return s;
    Epoch& e = next.epochs[0];
    e.time = t;
    e.x = prior.mean;
    if (Status s = attach(meas, e.x, e); !s) return s;
    next.prior = p;
    next.size = 1;
    return solve_and_commit(next);
  }

  /// Adds the state at time t, predicted from the newest by the motion model with input u,
  /// marginalising the oldest first when the window is full, and solves the window.
  /// u of a size known only at run time: refused with input_wrong_size unless it is Input's.
  template <DynamicSizeEigen U>
    requires FixedSizeEigen<Input>
  Status step(double t, const U& u, const Measurements& meas) {
    return with_size_checked<Input>(u, Problem::input_wrong_size, [&](const Input& f) { return step(t, f, meas); });
  }
  Status step(double t, const Input& u, const Measurements& meas) {
    if (!initialised()) return Status::invalid(Problem::time_not_set);
    if (!std::isfinite(t)) return Status::invalid(Problem::non_finite_dt);
    const Window& now = current();
    if (t < time()) return Status::invalid(Problem::out_of_order_time);
    const State& x_prev = newest();
    Epoch added;
    if (Status s = make_motion_factor(motion_, u, t - time(), x_prev, added.motion, opts_.limits); !s) return s;
    added.time = t;
    added.x = motion_.predict(x_prev, u, t - time(), nullptr);
    if (!all_finite(added.x)) return Status::failure(Problem::non_finite_prediction);
    if constexpr (affine_motion)
      if (!added.motion_blocks.compute(added.motion, x_prev, added.x)) return Status::failure(Problem::non_finite_prediction);
    if constexpr (plain_motion)
      if (!added.motion_blocks.compute(added.motion)) return Status::failure(Problem::non_finite_prediction);
    if (Status s = attach(meas, added.x, added); !s) return s;

    Window& next = spare();
    if (now.size == K) {
      if (Status s = marginalize_oldest(now, next.prior); !s) return s;
      for (int i = 1; i < K; ++i) next.epochs[static_cast<std::size_t>(i - 1)] = now.epochs[static_cast<std::size_t>(i)];
      next.size = K - 1;
    } else {
      next = now;
    }
    next.epochs[static_cast<std::size_t>(next.size)] = added;
    ++next.size;
    return solve_and_commit(next);
  }

  /// 1/2 |r|^2 of the window's factors at states xs (+Inf when a residual is not finite):
  /// what the solver minimises, exposed so that a test can compare minima with Ceres'.
  double cost(const Window& w, const std::array<State, K>& xs) const {
    double c = 0.5 * w.prior.evaluate(xs[0]).squaredNorm();
    for (int i = 0; i < w.size; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const Epoch& e = w.epochs[k];
      for (int j = 0; j < e.factor_count; ++j)
        c += 0.5 * e.factors[static_cast<std::size_t>(j)].evaluate(xs[k]).squaredNorm();
      if (i > 0) c += 0.5 * e.motion.evaluate(xs[k - 1], xs[k]).squaredNorm();
    }
    return std::isfinite(c) ? c : std::numeric_limits<double>::infinity();
  }

 private:
  const Window& current() const { return buffers_[static_cast<std::size_t>(active_)]; }
  Window& spare() { return buffers_[static_cast<std::size_t>(1 - active_)]; }
  std::size_t last() const { return static_cast<std::size_t>(current().size > 0 ? current().size - 1 : 0); }

  /// Makes the factors of the attached slots (validated as an EKF update validates).
  Status attach(const Measurements& meas, const State& x_lin, Epoch& e) const {
    if (meas.count < 0 || meas.count > C) return Status::invalid(Problem::measurement_count_above_capacity);
    e.factor_count = 0;
    for (int i = 0; i < meas.count; ++i) {
      const auto k = static_cast<std::size_t>(i);
      if (!meas.attached[k]) continue;
      auto& f = e.factors[static_cast<std::size_t>(e.factor_count)];
      if (Status s = make_measurement_factor<dim>(meas.models[k], meas.z[k], x_lin, f, opts_.limits); !s) return s;
      ++e.factor_count;
    }
    return Status{};
  }

  /// The factors on epochs[0] (prior, its measurements, the motion factor to epochs[1]) at the
  /// current solution, Schur-complemented into a prior on epochs[1].
  Status marginalize_oldest(const Window& w, PriorFactor<dim>& out) const {
    BlockTridiagonal<dim, 2> sys;
    sys.reset(2);
    const Epoch& e0 = w.epochs[0];
    const Epoch& e1 = w.epochs[1];
    bool ok = sys.add(w.prior, 0, e0.x);
    for (int j = 0; j < e0.factor_count; ++j) ok = ok && sys.add(e0.factors[static_cast<std::size_t>(j)], 0, e0.x);
    ok = ok && sys.add(e1.motion, 0, e0.x, e1.x);
    if (!ok) return Status::failure(Problem::non_finite_prediction);
    return marginalize_first(sys, e1.x, out);
  }

  /// Normal equations of the window's factors at xs into sys; false when a residual or a
  /// Jacobian is not finite.
  static bool linearize(const Window& w, const std::array<State, K>& xs, BlockTridiagonal<dim, K>& sys) {
    sys.reset(w.size);
    bool ok = sys.add(w.prior, 0, xs[0]);
    for (int i = 0; i < w.size && ok; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const Epoch& e = w.epochs[k];
      for (int j = 0; j < e.factor_count && ok; ++j) ok = sys.add(e.factors[static_cast<std::size_t>(j)], i, xs[k]);
      if (i > 0 && ok) {
        if constexpr (affine_motion || plain_motion)
          ok = sys.add(e.motion, e.motion_blocks, i - 1, xs[k - 1], xs[k]);
        else
          ok = sys.add(e.motion, i - 1, xs[k - 1], xs[k]);
      }
    }
    return ok;
  }

  /// Levenberg-Marquardt on the block-tridiagonal normal equations from the states in `w`.
  /// A trial point is linearised into the second system; its cost (a by-product) decides,
  /// and an accepted trial's system is the next iteration's, so no pass is spent on the cost
  /// alone.
  Status solve_and_commit(Window& w) {
    FixedLagReport rep;
    std::array<State, K> xs, trial;
    std::array<Vector<dim>, K> rhs, dx;
    for (int i = 0; i < w.size; ++i) xs[static_cast<std::size_t>(i)] = w.epochs[static_cast<std::size_t>(i)].x;
    int at = 0;  // sys_[at] is linearised at xs
    if (!linearize(w, xs, sys_[0])) return Status::failure(Problem::non_finite_prediction);
    rep.initial_cost = sys_[0].cost;
    double lambda = 0.0;
    bool converged = false, undamped = false;
    while (rep.iterations < opts_.max_iterations && !converged) {
      ++rep.iterations;
      const auto& sys = sys_[static_cast<std::size_t>(at)];
      if (chol_.factorize(sys, lambda) != Problem::none) {
        if (opts_.levenberg_marquardt && lambda < 1e12) {
          lambda = std::max(10.0 * lambda, opts_.min_lambda);
          continue;
        }
        return Status::failure(Problem::system_not_positive_definite);
      }
      undamped = lambda == 0.0;
      for (int i = 0; i < w.size; ++i) rhs[static_cast<std::size_t>(i)] = -sys.gradient[static_cast<std::size_t>(i)];
      chol_.solve(sys, rhs, dx);
      double largest = 0.0;
      for (int i = 0; i < w.size; ++i) {
        const auto k = static_cast<std::size_t>(i);
        trial[k] = xs[k] + dx[k];
        largest = std::max(largest, dx[k].cwiseAbs().maxCoeff());
      }
      if (!std::isfinite(largest)) return Status::failure(Problem::non_finite_state);
      converged = largest <= opts_.step_tolerance;
      if (converged && undamped) {
        // A step this small from an undamped system: take it without linearising there. The
        // cost can change only by rounding, and the covariance below comes from this
        // factorisation (its point within step_tolerance of the solution).
        xs = trial;
        break;
      }
      auto& next = sys_[static_cast<std::size_t>(1 - at)];
      const bool finite = linearize(w, trial, next);
      // LM takes only steps that do not raise the cost. At the minimum a step below the
      // tolerance may raise it by rounding: it ends the solve all the same.
      if (finite && (!opts_.levenberg_marquardt || next.cost <= sys.cost)) {
        xs = trial;
        at = 1 - at;
        lambda = lambda * 0.1 < opts_.min_lambda ? 0.0 : lambda * 0.1;
      } else if (!finite && !opts_.levenberg_marquardt) {
        return Status::failure(Problem::non_finite_prediction);
      } else if (!converged) {
        lambda = std::max(10.0 * lambda, opts_.min_lambda);
      }
    }
    rep.final_cost = sys_[static_cast<std::size_t>(at)].cost;  // at the last linearisation point
    report_ = rep;
    if (!converged) return Status::failure(Problem::not_converged);
    // The newest state's information is the last Schur complement of an undamped
    // factorisation: the converging iteration's when it was undamped (its point is within
    // step_tolerance of the solution), a fresh one at the solution otherwise.
    if (!undamped && chol_.factorize(sys_[static_cast<std::size_t>(at)], 0.0) != Problem::none)
      return Status::failure(Problem::system_not_positive_definite);
    const SquareMatrix<dim>& P = chol_.last_covariance();
    if (!all_finite(P)) return Status::failure(Problem::non_finite_covariance);
    for (int i = 0; i < w.size; ++i) w.epochs[static_cast<std::size_t>(i)].x = xs[static_cast<std::size_t>(i)];
    w.newest_cov = P;
    active_ = 1 - active_;
    return Status{};
  }

  Motion motion_;
  FixedLagOptions opts_;
  std::array<Window, 2> buffers_{};
  int active_ = 0;
  FixedLagReport report_{};
  std::array<BlockTridiagonal<dim, K>, 2> sys_{};
  BlockTridiagonalCholesky<dim, K> chol_{};
};

}  // namespace ctxfuse

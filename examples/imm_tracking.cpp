// An IMM tracking a vehicle that drives straight, turns left through 90 degrees and drives
// straight again, from noisy 2-D position fixes. Three modes over the same state (p, v):
//   0  constant velocity, low process noise     (straight driving)
//   1  constant velocity, high process noise    (anything the other two do not explain)
//   2  coordinated turn at a known rate         (the turn; a linear model for a known rate)
// Each fix runs one IMM cycle with one call, Imm::cycle(). The mode probabilities should
// move to the turn model during the turn and back to constant velocity after it;
// tests/examples/imm_tracking_test.cpp reads this program's output and checks that they do.
//
// Output, one line per fix (lines starting with '#' are comments, the rest whitespace-separated
// numbers, so that a test or a plotting script can read them):
//   t  truth_mode  mu_cv  mu_cv_high  mu_turn  most_probable  position_error_m
// truth_mode is the mode the vehicle is really in (0 straight, 2 turning).
//   build/release/examples/example_imm_tracking [seed]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>

#include "ctxfuse/filters/imm.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/policies/mixing.hpp"
#include "ctxfuse/sim/random.hpp"

namespace {
using namespace ctxfuse;
using L = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;

/// Coordinated turn at a known rate omega [rad/s] (counter-clockwise positive): the velocity
/// rotates by omega dt in each step and the position follows the arc. Its process noise is the
/// constant-velocity one (white acceleration of density accel_psd), for the small deviations
/// from a perfect turn.
struct KnownRateTurn {
  static constexpr int dim = L::size;
  using State = Vector<dim>;
  using Input = NoInput;
  double omega = 0.1;
  double accel_psd = 0.05;

  State predict(const State& x, const Input&, double dt, SquareMatrix<dim>* F) const {
    const SquareMatrix<dim> T = transition(dt);
    if (F) *F = T;
    return T * x;
  }
  SquareMatrix<dim> noise(const State& x, const Input& u, double dt) const {
    return models::ConstantVelocity<L, 2>{accel_psd}.noise(x, u, dt);
  }

 private:
  SquareMatrix<dim> transition(double dt) const {
    const double s = std::sin(omega * dt), c = std::cos(omega * dt);
    SquareMatrix<dim> T = SquareMatrix<dim>::Identity();
    L::cov<"p", "v">(T) << s / omega, -(1.0 - c) / omega, (1.0 - c) / omega, s / omega;
    L::cov<"v">(T) << c, -s, s, c;
    return T;
  }
};

struct FixTag {};  // the only kind of measurement here; every mode takes it

constexpr double kDt = 0.5;            // s between fixes
constexpr double kSpeed = 10.0;        // m/s
constexpr double kTurnRate = std::numbers::pi / 40.0;  // rad/s: 90 degrees in 20 s
constexpr double kTurnStart = 30.0, kTurnEnd = 50.0, kEnd = 90.0;  // s
constexpr double kFixSigma = 0.5;      // m, each axis
}  // namespace

int main(int argc, char** argv) {
  const unsigned long long seed = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 1;
  sim::Rng rng(seed);

  // The three modes. ConstantVelocity and the measurement model come with the library; a
  // mode may be any process model with predict() and noise() over the same state.
  auto modes = boost::hana::make_tuple(imm::make_mode(models::ConstantVelocity<L, 2>{0.05}),
                                       imm::make_mode(models::ConstantVelocity<L, 2>{5.0}),
                                       imm::make_mode(KnownRateTurn{kTurnRate, 0.05}));
  // p_ij per cycle (per fix): stay with probability 0.95, else switch to either other mode.
  policies::FixedTransition<3> mixing(policies::sticky_transition<3>(0.95));

  Gaussian<4> initial;
  initial.mean << 0.0, 0.0, kSpeed, 0.0;
  initial.cov = Vector<4>(1.0, 1.0, 4.0, 4.0).asDiagonal();
  imm::ImmOptions<3> options;
  // Which probabilities weight combined() between mix() and the close; with cycle() the
  // estimate is read after the close, where both are the posterior. The textbook choice:
  options.prior_weights = imm::PriorWeights::predicted;
  imm::Imm filter(mixing, modes, initial, Vector<3>(0.8, 0.1, 0.1), options);

  models::BlockObservation<L, "p"> fix;
  fix.R = SquareMatrix<2>::Identity() * (kFixSigma * kFixSigma);

  std::printf("# IMM tracking, seed %llu: modes 0 CV (low noise), 1 CV (high noise), 2 turn at %.2f deg/s\n", seed,
              kTurnRate * 180.0 / std::numbers::pi);
  std::printf("# straight until t = %.0f s, turning until %.0f s, straight until %.0f s\n", kTurnStart, kTurnEnd, kEnd);
  std::printf("# t truth_mode mu_cv mu_cv_high mu_turn most_probable position_error_m\n");
  Vector<4> truth = initial.mean;
  double sq_err[2] = {0, 0};
  int count[2] = {0, 0};
  for (double t = kDt; t <= kEnd + 1e-9; t += kDt) {
    // Truth: the same kinematics as the modes, without noise.
    const bool turning = t > kTurnStart + 1e-9 && t <= kTurnEnd + 1e-9;
    if (turning)
      truth = KnownRateTurn{kTurnRate}.predict(truth, {}, kDt, nullptr);
    else
      truth = models::ConstantVelocity<L, 2>{}.predict(truth, {}, kDt, nullptr);
    // Two named draws: the order in which a constructor's arguments are evaluated is unspecified.
    const double noise_x = rng.normal(), noise_y = rng.normal();
    const Vector<2> z(truth(0) + kFixSigma * noise_x, truth(1) + kFixSigma * noise_y);

    // One call: mix, predict every mode by kDt, correct every mode with the fix (and score
    // it), update the mode probabilities.
    const auto result = filter.cycle({}, kDt, imm::observe(FixTag{}, fix, z));
    if (!result.status()) {
      std::fprintf(stderr, "t = %.1f s: the IMM refused the cycle: %s\n", t,
                   describe(result.status().problem).data());
      return 1;
    }
    const Vector<3>& mu = filter.mode_probabilities();
    const double err = (L::get<"p">(filter.combined().mean) - truth.head<2>()).norm();
    sq_err[turning] += err * err;
    ++count[turning];
    std::printf("%.1f %d %.6f %.6f %.6f %d %.4f\n", t, turning ? 2 : 0, mu(0), mu(1), mu(2), filter.most_probable(), err);
  }
  std::printf("# RMS position error: straight %.3f m, turning %.3f m (fix noise %.2f m per axis)\n",
              std::sqrt(sq_err[0] / count[0]), std::sqrt(sq_err[1] / count[1]), kFixSigma);
  return 0;
}

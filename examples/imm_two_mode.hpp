// The core of examples/imm_two_mode.cpp: a two-mode IMM (quiet and manoeuvring constant
// velocity) tracking a target that drives straight, turns through 90 degrees and drives
// straight again, from 2-D position fixes. tests/examples/examples_test.cpp calls run() too
// and checks its numbers against an IMM written out by hand. docs/imm.md walks through it.
#pragma once

#include <boost/hana.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "ctxfuse/filters/imm.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/policies/mixing.hpp"
#include "ctxfuse/sim/random.hpp"

namespace imm_two_mode {
using namespace ctxfuse;

using L = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;
using Cv = models::ConstantVelocity<L, 2>;
using Fix = models::BlockObservation<L, "p">;
struct FixTag {};  // the one kind of measurement here; both modes take it

struct Settings {
  std::uint64_t seed = 1;
  double dt = 1.0;                   // [s] between fixes, one IMM cycle per fix
  int steps = 60;
  int turn_first = 21, turn_last = 30;  // the cycles (1-based) during which the target turns
  double speed = 10.0;               // [m/s]
  double turn_rate = std::numbers::pi / 20.0;  // [rad/s]: 90 degrees in 10 s
  double fix_sigma = 1.0;            // [m] per axis
  double q_quiet = 0.01;             // [m^2/s^3] mode 0's white acceleration density
  double q_manoeuvre = 4.0;          // [m^2/s^3] mode 1's
  double p_stay = 0.95;              // per cycle
  imm::ImmOptions<2> options{};      // the defaults: probability floor 1e-6, previous_posterior
};

using Filter = imm::Imm<policies::FixedTransition<2>, imm::Mode<Cv>, imm::Mode<Cv>>;

inline Filter make_filter(const Settings& s, const Gaussian<4>& initial, const Vector<2>& mu0) {
  auto modes = boost::hana::make_tuple(imm::make_mode(Cv{s.q_quiet}), imm::make_mode(Cv{s.q_manoeuvre}));
  policies::FixedTransition<2> mixing(policies::sticky_transition<2>(s.p_stay));
  return Filter(mixing, modes, initial, mu0, s.options);
}

struct Cycle {
  double t = 0.0;
  bool turning = false;
  Vector<4> truth;
  Vector<2> z;
  Status mixed, predicted;           // what mix() and predict() returned
  Vector<2> c;                       // predicted mode probabilities c_j (after mix)
  Gaussian<4> prior;                 // combined() after predict: weights as options.prior_weights says
  Gaussian<4> prior_predicted;       // combined(PriorWeights::predicted) after predict: the textbook's
  imm::UpdateResult<2> update;
  Vector<2> mu;                      // mode probabilities after the close
  std::array<Gaussian<4>, 2> mode;   // each mode's belief after the update
  Gaussian<4> combined;              // after the close
};

struct Run {
  Settings settings;
  Gaussian<4> initial;
  Vector<2> mu0;
  std::vector<Cycle> cycles;
};

inline Run run(const Settings& s = {}) {
  Run out;
  out.settings = s;
  out.initial.mean << 0.0, 0.0, s.speed, 0.0;
  out.initial.cov = Vector<4>(4.0, 4.0, 1.0, 1.0).asDiagonal();
  out.mu0 << 0.9, 0.1;
  Filter filter = make_filter(s, out.initial, out.mu0);
  Fix fix;
  fix.R = SquareMatrix<2>::Identity() * (s.fix_sigma * s.fix_sigma);

  sim::Rng rng(s.seed);
  Vector<4> truth = out.initial.mean;
  for (int k = 1; k <= s.steps; ++k) {
    Cycle c;
    c.t = k * s.dt;
    c.turning = k >= s.turn_first && k <= s.turn_last;
    // Truth: straight, or an arc at turn_rate (the velocity turns by turn_rate dt).
    const Vector<2> v = truth.tail<2>();
    if (c.turning) {
      const double w = s.turn_rate, sn = std::sin(w * s.dt), cs = std::cos(w * s.dt);
      truth.head<2>() += Vector<2>(sn * v.x() - (1.0 - cs) * v.y(), (1.0 - cs) * v.x() + sn * v.y()) / w;
      truth.tail<2>() = Vector<2>(cs * v.x() - sn * v.y(), sn * v.x() + cs * v.y());
    } else {
      truth.head<2>() += s.dt * v;
    }
    c.truth = truth;
    const double nx = rng.normal(), ny = rng.normal();  // in this order
    c.z = truth.head<2>() + s.fix_sigma * Vector<2>(nx, ny);

    // One IMM cycle, step by step (filter.cycle() does the same in one call).
    c.mixed = filter.mix();
    if (c.mixed) c.predicted = filter.predict({}, s.dt);
    if (!c.mixed || !c.predicted) {  // neither is refused here; a refusal ends the run
      out.cycles.push_back(c);
      break;
    }
    c.c = filter.predicted_probabilities();
    c.prior = filter.combined();
    c.prior_predicted = filter.combined(imm::PriorWeights::predicted);
    c.update = filter.update(FixTag{}, fix, c.z);
    filter.update_mode_probabilities();
    c.mu = filter.mode_probabilities();
    c.mode = {filter.mode_belief<0>(), filter.mode_belief<1>()};
    c.combined = filter.combined();
    out.cycles.push_back(c);
  }
  return out;
}

}  // namespace imm_two_mode

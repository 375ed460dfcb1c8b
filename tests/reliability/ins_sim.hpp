// What the simulated truths of the geodetic INS in tests/reliability share (the GNSS/INS
// consistency test and the soak): chaining increments for coning and sculling, and moving the
// truth's biases by the model's own Gauss-Markov processes.
#pragma once

#include <cmath>

#include "ctxfuse/models/ins_nav.hpp"
#include "ctxfuse/sim/random.hpp"

namespace ctxfuse::reliability {


/// Gives u the previous step's increments (none on the first step) and remembers u as the next
/// step's previous.
inline void chain(models::BodyIncrements& u, models::BodyIncrements& prev, bool first) {
  u.has_previous = !first;
  u.prev_dtheta = prev.dtheta;
  u.prev_dv = prev.dv;
  prev = u;
}

/// The truth's biases after a step of dt: the decay is in the model's predict, the driving
/// noise (the model's Q of the bias blocks) is added here.
template <class Model, class State>
void walk_biases(const Model& m, State& x, double dt, sim::Rng& rng) {
  x.template get<"bg">() += std::sqrt(m.gyro_bias.variance(dt)) * rng.normals<3>();
  x.template get<"ba">() += std::sqrt(m.accel_bias.variance(dt)) * rng.normals<3>();
}

}  // namespace ctxfuse::reliability

// The small types of the IMM (filters/imm.hpp): the options (with the two priors of the
// combined estimate), what an update and a whole cycle report, and the observation that
// Imm::cycle() takes. Apart from the class so that a reader sees the vocabulary first.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>

#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"
#include "ctxfuse/core/validation.hpp"

namespace ctxfuse::imm {

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

/// Which mode probabilities weight the combined estimate while a cycle is open (after mix(),
/// before update_mode_probabilities()). Once the cycle is closed both are the posterior mu_j.
///   predicted: the textbook prior (Bar-Shalom 11.6.6), c_j = sum_i p_ij mu_i, the probability
///     of mode j given the data up to the last closed cycle. It is what marginalising the mixed
///     beliefs gives: combined() right after mix() equals combined() right before it, and after
///     predict() it is the combined prediction x(k|k-1) = sum_j c_j x_j(k|k-1). Choose it when
///     the combined estimate is read between mix() and the close (a gate, an integrity check
///     or an output at a rate above the cycle's).
///   previous_posterior: the last closed cycle's mu_j. What the IMM always did, so it stays
///     the default: the region pipeline's UWB integrity check reads combined() between GNSS
///     epochs, and its published numbers were made this way. It ignores the transition matrix,
///     so the combined estimate jumps at every mix() by what the mixing moved between modes;
///     harmless where combined() is read only after the close.
/// The likelihoods of the cycle's updates enter neither: they enter at the close.
enum class PriorWeights : std::uint8_t { previous_posterior, predicted };

template <int R>
struct ImmOptions {
  double probability_floor = 1e-6;  // each mu_j is kept >= this (then renormalised)
  PriorWeights prior_weights = PriorWeights::previous_posterior;  // see PriorWeights
  FilterOptions filter{};
};

/// One measurement for Imm::cycle(): the arguments of Imm::update() in one value. The model is
/// copied (models are small plain structs), so an Observation may outlive the model it was
/// made from.
template <class Tag, class Meas, int M>
struct Observation {
  using TagType = Tag;
  Meas model;
  Vector<M> z;
  std::uint32_t mask = ~std::uint32_t{0};
};

/// `meas` is one measurement model for every mode or a hana::tuple with one per mode; `mask`
/// bit j lets mode j take it (as Imm::update()).
template <class Tag, class Meas, int M>
Observation<Tag, Meas, M> observe(Tag, Meas meas, const Vector<M>& z, std::uint32_t mask = ~std::uint32_t{0}) {
  return {std::move(meas), z, mask};
}

/// What one Imm::cycle() did. `predict` and `updates` are meaningful only when `mix` was
/// accepted; a refused mix() changes nothing and the cycle stops there.
template <int R, std::size_t K>
struct CycleResult {
  Status mix{};
  Status predict{};
  std::array<UpdateResult<R>, K> updates{};  // in the order the observations were given

  /// The first refusal of the cycle (mix, then predict); accepted when neither refused.
  const Status& status() const { return mix.accepted() ? predict : mix; }
};

}  // namespace ctxfuse::imm

// The modes of the IMM (filters/imm.hpp): what a mode is (process model, the measurement tags
// it takes, its gate), how its belief is stored (Gaussian, or nominal and error covariance for
// error-state models), and how a mode is scored on a measurement it does not take.
#pragma once

#include <boost/hana.hpp>

#include <type_traits>
#include <utility>

#include "ctxfuse/core/concepts.hpp"
#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"
#include "ctxfuse/core/validation.hpp"
#include "ctxfuse/filters/kalman_update.hpp"
#include "ctxfuse/filters/score.hpp"
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
template <ProcessModel Model, class Taken = AcceptsAll, GatePolicy Gate = policies::NoGate>
struct Mode {
  using ProcessModelType = Model;
  using TakenTags = Taken;
  using GateType = Gate;
  Model model{};
  Gate gate{};
};

template <class Model, class Taken = AcceptsAll, class Gate = policies::NoGate>
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

/// The point of a belief: the mean of a Gaussian, the nominal of an error-state belief.
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

/// Innovation log-likelihood of a mode's prediction on a measurement it does not take, without
/// correcting it: outcome `gated` (scored, not applied), NIS and log N(y; 0, S) filled in, as
/// ctxfuse::score computes them.
template <int N, class Meas, class B, int M>
Status score_prediction(const Meas& meas, const B& belief, const Vector<M>& z, const FilterOptions& options) {
  static_assert(std::remove_cvref_t<decltype(belief.cov)>::RowsAtCompileTime == N);
  Status s = ctxfuse::score(meas, belief, z, policies::NoGate{}, options);
  if (s.accepted()) s.outcome = Outcome::gated;
  return s;
}

}  // namespace detail

}  // namespace ctxfuse::imm

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
/// correcting it: outcome `gated` (scored, not applied), NIS and log N(y; 0, S) filled in.
template <int N, class Meas, class B, int M>
Status score_prediction(const Meas& meas, const B& belief, const Vector<M>& z, const FilterOptions& options) {
  const SquareMatrix<M> Rm = meas.noise(point(belief));
  if (Problem p = check_measurement<M>(z, Rm, options); p != Problem::none) return Status::invalid(p);
  if (Problem p = ctxfuse::detail::model_check(meas, z); p != Problem::none) return Status::invalid(p);
  Matrix<M, N> H;
  const Vector<M> zp = meas.predict(point(belief), &H);
  const Vector<M> y = ctxfuse::detail::innovation(meas, z, zp);
  if (!H.allFinite() || !y.allFinite()) return Status::failure(Problem::non_finite_prediction);
  SquareMatrix<M> S = H * belief.cov * H.transpose();
  S += Rm;
  symmetrize(S);
  const InnovationSolve<M> solve(S);
  if (!solve.ok) return Status::failure(Problem::innovation_not_positive_definite);
  Status s;
  s.outcome = Outcome::gated;
  s.dof = M;
  s.nis = solve.nis(y);
  s.log_likelihood = solve.log_likelihood(s.nis);
  return s;
}

}  // namespace detail

}  // namespace ctxfuse::imm

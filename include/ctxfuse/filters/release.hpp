// A gated aiding source with a lock-out release, in one place for every error-state pipeline
// (the GNSS/INS pass and its simulation study). policies::SourceHealth watches the source's
// outcomes; once it declares a lock-out, the next measurement is released: the covariance of
// the block it observes (position, velocity) is widened, by the same amount on each axis, just
// enough that its innovation lies on the gate's boundary (policies::variance_to_gate), and the
// measurement then updates the widened belief as usual.
//
// Why widen to the boundary. An update of the unwidened covariance with the gate off takes a
// fix 100 m off at the confidence of a converged filter and drags velocity and attitude through
// their correlations with the position. A reset of the block (dropping its correlations)
// recovers from a jump too, but after a real outage it is through those correlations that a
// late fix corrects the heading (docs/reliability.md, "The NLOS UWB and GNSS/INS pipelines").
#pragma once

#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/policies/gating.hpp"
#include "ctxfuse/policies/health.hpp"

namespace ctxfuse::eskf {

/// The measurement z of block Block, released: that block's variance widened until the
/// innovation lies on the gate's boundary (unwidened when it lies inside already), then an
/// ungated update. The belief is written only when the update is accepted.
template <FixedString Block, ErrorStateProcessModel Model, class Meas, GatePolicy Gate>
  requires MeasurementModel<Meas, typename Model::State, Model::dim>
Status release(const Model& model, const Meas& meas, Belief<Model>& belief, const Vector<Meas::dim>& z,
               const Gate& gate) {
  constexpr int N = Model::dim;
  constexpr int M = Meas::dim;
  using L = typename Model::ErrorLayout;
  constexpr int o = L::template offset<Block>();
  constexpr int n = L::template size_of<Block>();
  Matrix<M, N> H;
  const Vector<M> y = ctxfuse::detail::innovation(meas, z, meas.predict(belief.nominal, &H));
  const SquareMatrix<M> S0 = H * belief.cov * H.transpose() + meas.noise(belief.nominal);
  const Matrix<M, n> Hb = H.template middleCols<n>(o);
  const double added = policies::variance_to_gate<M>(y, S0, Hb * Hb.transpose(), gate.threshold(M));
  if (!(added >= 0.0)) return Status::invalid(Problem::non_finite_prediction);
  if (added == 0.0) return update(model, meas, belief, z);
  Belief<Model> widened = belief;
  widened.cov.template block<n, n>(o, o).diagonal().array() += added;
  const Status st = update(model, meas, widened, z);
  if (st.accepted()) belief = widened;
  return st;
}

/// One measurement of a source that `health` watches: released (above) when the health says
/// the source is locked out at t, else through the gate; the outcome is recorded in `health`.
/// `released`, when given, is set to whether this measurement was released and accepted.
template <FixedString Block, ErrorStateProcessModel Model, class Meas, GatePolicy Gate>
  requires MeasurementModel<Meas, typename Model::State, Model::dim>
Status update_or_release(const Model& model, const Meas& meas, Belief<Model>& belief, const Vector<Meas::dim>& z,
                         const Gate& gate, policies::SourceHealth& health, double t, bool* released = nullptr) {
  const bool release_now = health.lockout(t);
  const Status st = release_now ? release<Block>(model, meas, belief, z, gate) : update(model, meas, belief, z, gate);
  health.record(t, st);
  if (released) *released = release_now && st.accepted();
  return st;
}

}  // namespace ctxfuse::eskf

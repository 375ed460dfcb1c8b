// The stateful wrapper shared by Ekf and Eskf: a belief, a clock, the options and the gate
// around a set of stateless steps (`Steps::predict`, `Steps::update`), so that the timed API
// and its out-of-order checks exist once.
#pragma once

#include <utility>

#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"
#include "ctxfuse/core/validation.hpp"
#include "ctxfuse/filters/filter_clock.hpp"
#include "ctxfuse/filters/score.hpp"

namespace ctxfuse::detail {

template <class Model, class Gate, class BeliefT, class Steps>
class StatefulFilter {
 public:
  static constexpr int dim = Model::dim;
  using Input = typename Model::Input;
  using Belief = BeliefT;

  StatefulFilter(Model model, Belief initial, FilterOptions options = {}, Gate gate = {})
      : model_(std::move(model)), belief_(std::move(initial)), options_(options), gate_(std::move(gate)) {}

  const Belief& belief() const { return belief_; }
  const Model& model() const { return model_; }
  const Gate& gate() const { return gate_; }
  const FilterOptions& options() const { return options_; }
  double time() const { return clock_.time(); }
  void set_time(double t) { clock_.set(t); }
  void reset(const Belief& b) { belief_ = b; }

  /// Predict by dt. When the filter has a time (set_time, predict_to) an accepted step moves
  /// it on by dt, so predict and predict_to can be mixed without predicting an interval twice.
  Status predict(const Input& u, double dt) {
    const Status s = Steps::predict(model_, belief_, u, dt, options_);
    if (s && clock_.is_set()) clock_.set(clock_.time() + dt);
    return s;
  }

  /// Predict from the filter time to `t`; out-of-order or unset time is rejected.
  Status predict_to(double t, const Input& u) {
    double dt = 0.0;
    if (Problem p = clock_.dt_to(t, dt); p != Problem::none) return Status::invalid(p);
    Status s = Steps::predict(model_, belief_, u, dt, options_);
    if (s) clock_.set(t);
    return s;
  }

  template <class Meas>
  Status update(const Meas& meas, const Vector<Meas::dim>& z) {
    return Steps::update(model_, meas, belief_, z, gate_, options_);
  }

  /// What update(meas, z) would report (NIS, log-likelihood, the gate's verdict), without
  /// updating (filters/score.hpp).
  template <class Meas>
  Status score(const Meas& meas, const Vector<Meas::dim>& z) const {
    return ctxfuse::score(meas, belief_, z, gate_, options_);
  }

  // Arguments whose size is known only at run time (VectorXd, Map, dynamic blocks): the size
  // is checked before anything is read, and a wrong one is refused (core/validation.hpp).
  template <DynamicSizeEigen U>
    requires FixedSizeEigen<Input>
  Status predict(const U& u, double dt) {
    return with_size_checked<Input>(u, Problem::input_wrong_size, [&](const Input& f) { return predict(f, dt); });
  }
  template <DynamicSizeEigen U>
    requires FixedSizeEigen<Input>
  Status predict_to(double t, const U& u) {
    return with_size_checked<Input>(u, Problem::input_wrong_size, [&](const Input& f) { return predict_to(t, f); });
  }
  template <class Meas, DynamicSizeEigen Z>
  Status update(const Meas& meas, const Z& z) {
    return with_size_checked<Vector<Meas::dim>>(z, Problem::measurement_wrong_size,
                                                [&](const Vector<Meas::dim>& f) { return update(meas, f); });
  }
  template <class Meas, DynamicSizeEigen Z>
  Status score(const Meas& meas, const Z& z) const {
    return ctxfuse::score(meas, belief_, z, gate_, options_);
  }

 private:
  Model model_;
  Belief belief_;
  FilterOptions options_;
  Gate gate_;
  FilterClock clock_;
};

}  // namespace ctxfuse::detail

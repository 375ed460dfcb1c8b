// Federated Kalman filter (Carlson 1990): L local EKFs over the same process model, each
// correcting with its own sensor, and a master filter that fuses their estimates in
// information form and resets them (fusion-reset mode):
//   P_g = (sum_i P_i^-1)^-1,   x_g = P_g sum_i P_i^-1 x_i,
//   then P_i = P_g / beta_i, x_i = x_g, with information-sharing factors beta_i > 0, sum 1.
// The process noise of local filter i is Q / beta_i (its share of the common process
// information), so that fusion does not count the common dynamics L times. A measurement
// given to several local filters should likewise be given with R / beta_i each
// (`shared_update`), or to one of them only.
//
// Angles: when the model defines difference()/inject() (e.g. the planar model wraps the
// heading), fusion happens in differences around local filter 0's estimate,
// x_g = x_0 [+] P_g sum_i P_i^-1 (x_i [-] x_0), which is the formula above for plain vectors.
// Nothing allocates; fusion uses Cholesky solves, and a covariance that is not positive
// definite fails the fusion (status, nothing changed).
// Failures: the operations report a Status like every other filter (nothing changed when not
// accepted); only the constructor throws (std::invalid_argument), for sharing factors beta_i
// that are not > 0 or do not sum to 1, a configuration error no step could recover from.
#pragma once

#include <Eigen/Cholesky>

#include <array>
#include <cmath>
#include <string>

#include "ctxfuse/core/concepts.hpp"
#include "ctxfuse/core/error.hpp"
#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/core/retraction.hpp"
#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/policies/gating.hpp"

namespace ctxfuse::fkf {

namespace detail {
/// Q / beta for the local filter's share of the process information.
template <class Model>
struct SharedProcess {
  using State = typename Model::State;
  using Input = typename Model::Input;
  static constexpr int dim = Model::dim;
  Model inner;
  double beta = 1.0;

  State predict(const State& x, const Input& u, double dt, SquareMatrix<dim>* F) const { return inner.predict(x, u, dt, F); }
  SquareMatrix<dim> noise(const State& x, const Input& u, double dt) const { return inner.noise(x, u, dt) / beta; }
  Problem check_input(const Input& u) const { return ctxfuse::detail::model_input_check(inner, u); }
};
}  // namespace detail

/// Information-form fusion of L Gaussian estimates (Model only for the angle-aware
/// difference/inject). Leaves `out` untouched unless accepted: a local or the fused
/// information that is not positive definite is covariance_not_positive_definite, a fused
/// result that is not finite non_finite_covariance or non_finite_state (numerical failures:
/// the locals are the filter's own).
template <class Model, int N, std::size_t L>
Status fuse(const Model& model, const std::array<Gaussian<N>, L>& locals, Gaussian<N>& out) {
  static_assert(L >= 1);
  SquareMatrix<N> info = SquareMatrix<N>::Zero();
  Vector<N> info_state = Vector<N>::Zero();
  const Vector<N>& ref = locals[0].mean;
  for (const auto& b : locals) {
    Eigen::LLT<SquareMatrix<N>> llt(b.cov);
    if (llt.info() != Eigen::Success) return Status::failure(Problem::covariance_not_positive_definite);
    const SquareMatrix<N> Pinv = llt.solve(SquareMatrix<N>::Identity());
    info += Pinv;
    info_state += Pinv * state_difference(model, b.mean, ref);
  }
  symmetrize(info);
  Eigen::LLT<SquareMatrix<N>> llt(info);
  if (llt.info() != Eigen::Success) return Status::failure(Problem::covariance_not_positive_definite);
  SquareMatrix<N> Pg = llt.solve(SquareMatrix<N>::Identity());
  symmetrize(Pg);
  const Vector<N> dx = llt.solve(info_state);
  if (!Pg.allFinite()) return Status::failure(Problem::non_finite_covariance);
  if (!dx.allFinite()) return Status::failure(Problem::non_finite_state);
  out.mean = state_inject(model, ref, dx);
  out.cov = Pg;
  return Status{};
}

/// L local EKFs and the master fusion with reset.
template <VectorProcessModel Model, int L, GatePolicy Gate = policies::NoGate>
class FederatedFilter {
 public:
  static constexpr int N = Model::dim;
  using Input = typename Model::Input;
  using Belief = Gaussian<N>;

  /// What the constructor would refuse (invalid_setting): a share not > 0, or shares whose sum
  /// is not 1 (within 1e-9).
  static SettingCheck check_shares(const std::array<double, L>& beta) {
    constexpr SettingCheck refused = SettingCheck::refuse("the shares beta_i must be > 0 and sum to 1");
    double s = 0.0;
    for (double b : beta) {
      if (!(b > 0.0)) return refused;
      s += b;
    }
    return std::abs(s - 1.0) <= 1e-9 ? SettingCheck{} : refused;
  }

  FederatedFilter(Model model, const Belief& initial, const std::array<double, L>& beta, FilterOptions options = {},
                  Gate gate = {})
      : model_(std::move(model)), beta_(beta), options_(options), gate_(std::move(gate)) {
    if (!check_shares(beta)) {
      std::string shares;
      for (double b : beta) shares += (shares.empty() ? "" : ", ") + std::to_string(b);
      ctxfuse::detail::invalid_setting("FederatedFilter: the shares beta_i must be > 0 and sum to 1, got " + shares);
    }
    global_ = initial;
    reset_locals();
  }

  const Belief& global() const { return global_; }
  /// Local filter i's belief; i must be in [0, L) (an accessor has no status to report with).
  const Belief& local(int i) const { return locals_[static_cast<std::size_t>(i)]; }
  const std::array<double, L>& beta() const { return beta_; }

  /// Predicts every local filter with its share of the process noise; all or nothing.
  Status predict(const Input& u, double dt) {
    auto next = locals_;
    for (int i = 0; i < L; ++i) {
      const detail::SharedProcess<Model> shared{model_, beta_[static_cast<std::size_t>(i)]};
      Status s = ekf::predict(shared, next[static_cast<std::size_t>(i)], u, dt, options_);
      if (!s.accepted()) return s;
    }
    locals_ = next;
    return Status{};
  }

  /// Corrects local filter `i` only; an i outside [0, L) is local_filter_index_out_of_range.
  template <class Meas>
  Status update(int i, const Meas& meas, const Vector<Meas::dim>& z) {
    if (i < 0 || i >= L) return Status::invalid(Problem::local_filter_index_out_of_range);
    return ekf::update<N>(meas, locals_[static_cast<std::size_t>(i)], z, gate_, options_);
  }

  // Arguments whose size is known only at run time: checked first, a wrong one refused.
  template <DynamicSizeEigen U>
    requires FixedSizeEigen<Input>
  Status predict(const U& u, double dt) {
    return with_size_checked<Input>(u, Problem::input_wrong_size, [&](const Input& f) { return predict(f, dt); });
  }
  template <class Meas, DynamicSizeEigen Z>
  Status update(int i, const Meas& meas, const Z& z) {
    return with_size_checked<Vector<Meas::dim>>(z, Problem::measurement_wrong_size,
                                                [&](const Vector<Meas::dim>& f) { return update(i, meas, f); });
  }

  /// Replaces the global estimate and resets the locals from it (P_i = P_g / beta_i), e.g. to
  /// widen the covariance after a gate lock-out. Rejects (changes nothing) a belief that is
  /// not finite or whose covariance is not positive definite.
  Status reset(const Belief& global) {
    if (!all_finite(global.mean)) return Status::invalid(Problem::non_finite_state);
    if (!all_finite(global.cov)) return Status::invalid(Problem::non_finite_covariance);
    if (!is_positive_definite(global.cov)) return Status::invalid(Problem::covariance_not_positive_definite);
    global_ = global;
    reset_locals();
    return Status{};
  }

  /// Fuses the local estimates into the global one and resets the locals from it; nothing
  /// changes unless accepted (the failures of fuse()).
  Status fuse_and_reset() {
    Belief g;
    if (Status s = fuse(model_, locals_, g); !s.accepted()) return s;
    global_ = g;
    reset_locals();
    return Status{};
  }

 private:
  void reset_locals() {
    for (int i = 0; i < L; ++i) {
      locals_[static_cast<std::size_t>(i)].mean = global_.mean;
      locals_[static_cast<std::size_t>(i)].cov = global_.cov / beta_[static_cast<std::size_t>(i)];
    }
  }

  Model model_;
  std::array<double, L> beta_;
  FilterOptions options_;
  Gate gate_;
  Belief global_;
  std::array<Belief, L> locals_;
};

}  // namespace ctxfuse::fkf

// Checks of a model's analytic Jacobians against central differences, on the manifold where the
// model has one: the battery our own model tests run, shipped for users' models (a model whose
// Jacobian or declared block pattern is wrong gives a filter that is wrong without any error).
//
//   ctxfuse::testing::check_transition(model, x, u, dt)     F of a process model: d f(x) / dx for
//                                                            a vector state, d (f(x [+] e) [-] f(x)) / de
//                                                            at e = 0 for an error-state model
//   ctxfuse::testing::check_reset(model, x, dx)             G = d ((x [+] e) [-] (x [+] dx)) / de at e = dx
//   ctxfuse::testing::check_measurement(meas, x)            H of a measurement on a vector state
//   ctxfuse::testing::check_measurement(meas, model, x)     H on an error-state model's state,
//                                                            d h(x [+] e) / de at e = 0
//
// Each also checks the block pattern the model declares (`transition_blocks`, `reset_blocks`,
// `jacobian_columns`, core/block_sparsity.hpp) against the numerical Jacobian: every entry
// outside the declared blocks zero, identity blocks the identity, diagonal blocks diagonal. A
// check returns a JacobianReport (true when it passed; otherwise what failed, where, and both
// values), so it runs under any test framework or none. Nothing in the library includes this
// header. GoogleTest's namespace is ::testing: after `using namespace ctxfuse;` name either one
// in full (::testing, ctxfuse::testing) or through an alias.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <ostream>
#include <span>
#include <string>
#include <utility>

#include "ctxfuse/core/block_sparsity.hpp"
#include "ctxfuse/core/concepts.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse::testing {

struct JacobianOptions {
  double step = 1e-6;              // central-difference step of every coordinate ...
  std::span<const double> steps;   // ... or one per coordinate (size: the error dimension)
  double tolerance = 1e-7;         // on |analytic - numerical| / max(1, |numerical|), and on
                                   // |numerical| where a declared pattern says 0 (|numerical - 1|: 1)
};

struct JacobianReport {
  std::string what;  // "transition", "reset", "measurement", with " pattern" for a declared pattern
  bool passed = true;
  std::string problem;          // empty when passed
  int row = -1, col = -1;       // the worst entry
  double analytic = 0.0, numerical = 0.0;
  double max_error = 0.0;       // the largest scaled error over the matrix
  explicit operator bool() const { return passed; }
};

inline std::ostream& operator<<(std::ostream& os, const JacobianReport& r) {
  os << r.what << ": " << (r.passed ? "passed" : "FAILED");
  if (!r.problem.empty()) os << " (" << r.problem << ")";
  if (r.row >= 0) os << ", worst entry (" << r.row << ", " << r.col << "): analytic " << r.analytic << ", numerical " << r.numerical;
  return os << ", max scaled error " << r.max_error;
}

namespace detail {

template <int N>
bool steps_fit(const JacobianOptions& o) {
  return o.steps.empty() || o.steps.size() == static_cast<std::size_t>(N);
}

template <int M, int N, class F>
Matrix<M, N> central_jacobian_at(F&& f, const Vector<N>& x, const JacobianOptions& o) {
  Matrix<M, N> J;
  for (int i = 0; i < N; ++i) {
    const double h = o.steps.empty() ? o.step : o.steps[static_cast<std::size_t>(i)];
    Vector<N> xp = x, xm = x;
    xp(i) += h;
    xm(i) -= h;
    J.col(i) = (f(xp) - f(xm)) / (2.0 * h);
  }
  return J;
}

inline JacobianReport failed(std::string what, std::string problem) {
  JacobianReport r;
  r.what = std::move(what);
  r.passed = false;
  r.problem = std::move(problem);
  return r;
}

template <int M, int N>
JacobianReport compare(std::string what, const Matrix<M, N>& analytic, const Matrix<M, N>& numerical, double tolerance) {
  JacobianReport r;
  r.what = std::move(what);
  if (!analytic.allFinite()) {
    r.passed = false;
    r.problem = "the analytic Jacobian is not finite";
  }
  for (int i = 0; i < M; ++i)
    for (int j = 0; j < N; ++j) {
      double e = std::abs(analytic(i, j) - numerical(i, j)) / std::max(1.0, std::abs(numerical(i, j)));
      if (std::isnan(e)) e = std::numeric_limits<double>::infinity();
      if (r.row < 0 || e > r.max_error) {
        r.max_error = e;
        r.row = i;
        r.col = j;
        r.analytic = analytic(i, j);
        r.numerical = numerical(i, j);
      }
    }
  if (!(r.max_error <= tolerance) && r.passed) {
    r.passed = false;
    r.problem = "analytic and numerical Jacobians differ by more than the tolerance";
  }
  return r;
}

/// What a block pattern says of entry (i, j): 0 (outside every block), 1 (on an identity
/// block's diagonal), or -1 (free).
template <auto Pat>
int pattern_value(int i, int j) {
  using L = typename decltype(Pat)::layout;
  for (std::size_t k = 0; k < decltype(Pat)::size; ++k) {
    const auto rb = static_cast<std::size_t>(Pat.row[k]);
    const auto cb = static_cast<std::size_t>(Pat.col[k]);
    const int r0 = L::offsets[rb], c0 = L::offsets[cb];
    if (i < r0 || i >= r0 + L::sizes[rb] || j < c0 || j >= c0 + L::sizes[cb]) continue;
    if (Pat.kind[k] == BlockKind::dense) return -1;
    if (i - r0 != j - c0) return 0;
    return Pat.kind[k] == BlockKind::identity ? 1 : -1;
  }
  return 0;
}

template <auto Pat>
bool column_declared(int j) {
  using L = typename decltype(Pat)::layout;
  for (std::size_t k = 0; k < decltype(Pat)::size; ++k) {
    const auto b = static_cast<std::size_t>(Pat.block[k]);
    if (j >= L::offsets[b] && j < L::offsets[b] + L::sizes[b]) return true;
  }
  return false;
}

template <auto Pat, int M, int N>
JacobianReport check_block_pattern(std::string what, const Matrix<M, N>& numerical, double tolerance) {
  JacobianReport r;
  r.what = std::move(what);
  for (int i = 0; i < M; ++i)
    for (int j = 0; j < N; ++j) {
      const int v = pattern_value<Pat>(i, j);
      if (v < 0) continue;
      const double e = std::abs(numerical(i, j) - v);
      if (e > r.max_error || std::isnan(e)) {
        r.max_error = std::isnan(e) ? std::numeric_limits<double>::infinity() : e;
        r.row = i;
        r.col = j;
        r.analytic = v;
        r.numerical = numerical(i, j);
      }
    }
  if (!(r.max_error <= tolerance)) {
    r.passed = false;
    r.problem = "the declared block pattern says this entry is " + std::to_string(static_cast<int>(r.analytic));
  }
  return r;
}

template <auto Pat, int M, int N>
JacobianReport check_column_pattern(std::string what, const Matrix<M, N>& numerical, double tolerance) {
  JacobianReport r;
  r.what = std::move(what);
  for (int j = 0; j < N; ++j) {
    if (column_declared<Pat>(j)) continue;
    for (int i = 0; i < M; ++i) {
      const double e = std::abs(numerical(i, j));
      if (e > r.max_error || std::isnan(e)) {
        r.max_error = std::isnan(e) ? std::numeric_limits<double>::infinity() : e;
        r.row = i;
        r.col = j;
        r.numerical = numerical(i, j);
      }
    }
  }
  if (!(r.max_error <= tolerance)) {
    r.passed = false;
    r.problem = "the declared jacobian_columns leave this column out";
  }
  return r;
}

template <class T>
concept DeclaresTransitionBlocks = requires { T::transition_blocks; };
template <class T>
concept DeclaresResetBlocks = requires { T::reset_blocks; };
template <class T>
concept DeclaresJacobianColumns = requires { T::jacobian_columns; };
template <class T>
concept HasResetJacobian = requires(const T& m, const typename T::State& x, const Vector<T::dim>& dx) {
  { m.reset_jacobian(x, dx) } -> std::convertible_to<SquareMatrix<T::dim>>;
};

}  // namespace detail

/// The transition Jacobian F of a process model (and its declared transition_blocks).
template <ProcessModel Model>
JacobianReport check_transition(const Model& m, const typename Model::State& x, const typename Model::Input& u,
                                double dt, const JacobianOptions& o = {}) {
  constexpr int N = Model::dim;
  if (!detail::steps_fit<N>(o)) return detail::failed("transition", "steps must be empty or hold one step per coordinate");
  SquareMatrix<N> F = SquareMatrix<N>::Constant(std::numeric_limits<double>::quiet_NaN());
  const typename Model::State fx = m.predict(x, u, dt, &F);
  SquareMatrix<N> F_num;
  if constexpr (VectorProcessModel<Model>) {
    F_num = detail::central_jacobian_at<N, N>([&](const Vector<N>& s) -> Vector<N> { return m.predict(s, u, dt, nullptr); }, x, o);
  } else {
    static_assert(ErrorStateProcessModel<Model>, "a process model on a non-vector state needs inject and difference");
    F_num = detail::central_jacobian_at<N, N>(
        [&](const Vector<N>& e) -> Vector<N> { return m.difference(m.predict(m.inject(x, e), u, dt, nullptr), fx); },
        Vector<N>::Zero(), o);
  }
  JacobianReport r = detail::compare("transition", F, F_num, o.tolerance);
  if (!r) return r;
  if constexpr (detail::DeclaresTransitionBlocks<Model>) {
    JacobianReport p = detail::check_block_pattern<Model::transition_blocks>("transition pattern", F_num, o.tolerance);
    if (!p) return p;
  }
  return r;
}

/// The reset Jacobian G of an error-state model after injecting dx (and its declared
/// reset_blocks): the error about x [+] dx as a function of the error about x.
template <ErrorStateProcessModel Model>
JacobianReport check_reset(const Model& m, const typename Model::State& x, const Vector<Model::dim>& dx,
                           const JacobianOptions& o = {}) {
  constexpr int N = Model::dim;
  static_assert(detail::HasResetJacobian<Model>, "the model declares no reset_jacobian");
  if (!detail::steps_fit<N>(o)) return detail::failed("reset", "steps must be empty or hold one step per coordinate");
  const typename Model::State x_new = m.inject(x, dx);
  const SquareMatrix<N> G = m.reset_jacobian(x, dx);
  const SquareMatrix<N> G_num = detail::central_jacobian_at<N, N>(
      [&](const Vector<N>& e) -> Vector<N> { return m.difference(m.inject(x, e), x_new); }, dx, o);
  JacobianReport r = detail::compare("reset", G, G_num, o.tolerance);
  if (!r) return r;
  if constexpr (detail::DeclaresResetBlocks<Model>) {
    JacobianReport p = detail::check_block_pattern<Model::reset_blocks>("reset pattern", G_num, o.tolerance);
    if (!p) return p;
  }
  return r;
}

/// d f(x) / d x at x for f: R^N -> R^M, central differences with step h per coordinate.
template <int M, int N, class F>
Matrix<M, N> central_jacobian(F&& f, const Vector<N>& x, double h = 1e-6) {
  JacobianOptions o;
  o.step = h;
  return detail::central_jacobian_at<M, N>(std::forward<F>(f), x, o);
}

namespace detail {
template <class Meas, int N>
JacobianReport finish_measurement(const Matrix<Meas::dim, N>& H, const Matrix<Meas::dim, N>& H_num, const JacobianOptions& o) {
  JacobianReport r = compare("measurement", H, H_num, o.tolerance);
  if (!r) return r;
  if constexpr (DeclaresJacobianColumns<Meas>) {
    JacobianReport p = check_column_pattern<Meas::jacobian_columns>("measurement pattern", H_num, o.tolerance);
    if (!p) return p;
  }
  return r;
}
}  // namespace detail

/// The measurement Jacobian H on a vector state (and the declared jacobian_columns).
template <class Meas, int N>
  requires MeasurementModel<Meas, Vector<N>, N>
JacobianReport check_measurement(const Meas& h, const Vector<N>& x, const JacobianOptions& o = {}) {
  constexpr int M = Meas::dim;
  if (!detail::steps_fit<N>(o)) return detail::failed("measurement", "steps must be empty or hold one step per coordinate");
  Matrix<M, N> H = Matrix<M, N>::Constant(std::numeric_limits<double>::quiet_NaN());
  const Vector<M> z0 = h.predict(x, &H);
  const Matrix<M, N> H_num = detail::central_jacobian_at<M, N>(
      [&](const Vector<N>& s) -> Vector<M> {
        const Vector<M> z = h.predict(s, nullptr);
        if constexpr (requires { h.residual(z, z0); }) return h.residual(z, z0) + z0;
        else return z;
      },
      x, o);
  return detail::finish_measurement<Meas, N>(H, H_num, o);
}

/// The measurement Jacobian H on an error-state model's state: d h(x [+] e) / de at e = 0.
template <class Meas, ErrorStateProcessModel Model>
  requires MeasurementModel<Meas, typename Model::State, Model::dim>
JacobianReport check_measurement(const Meas& h, const Model& m, const typename Model::State& x, const JacobianOptions& o = {}) {
  constexpr int M = Meas::dim, N = Model::dim;
  if (!detail::steps_fit<N>(o)) return detail::failed("measurement", "steps must be empty or hold one step per coordinate");
  Matrix<M, N> H = Matrix<M, N>::Constant(std::numeric_limits<double>::quiet_NaN());
  const Vector<M> z0 = h.predict(x, &H);
  const Matrix<M, N> H_num = detail::central_jacobian_at<M, N>(
      [&](const Vector<N>& e) -> Vector<M> {
        const Vector<M> z = h.predict(m.inject(x, e), nullptr);
        if constexpr (requires { h.residual(z, z0); }) return h.residual(z, z0) + z0;
        else return z;
      },
      Vector<N>::Zero(), o);
  return detail::finish_measurement<Meas, N>(H, H_num, o);
}

}  // namespace ctxfuse::testing

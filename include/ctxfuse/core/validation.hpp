// Input checks shared by every filter step. Each returns the first Problem found, or
// Problem::none; the caller turns it into a Status before touching the estimate.
#pragma once

#include <cmath>
#include <concepts>
#include <limits>
#include <type_traits>

#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse {

/// Limits a filter enforces on what it is given. The defaults reject only the absurd; tighten
/// them to what the sensors can physically produce.
struct FilterOptions {
  double max_dt = 10.0;                  // [s] longer gaps call for re-initialisation, not prediction
  double max_abs_measurement = 1e9;      // any element of z
  double max_abs_input = 1e6;            // any element of u (Eigen inputs, or via max_abs())
};

inline Problem check_dt(double dt, const FilterOptions& opts) {
  if (!std::isfinite(dt)) return Problem::non_finite_dt;
  if (dt <= 0.0) return Problem::non_positive_dt;
  if (dt > opts.max_dt) return Problem::dt_above_maximum;
  return Problem::none;
}

template <class Input>
Problem check_input(const Input& u, const FilterOptions& opts) {
  if constexpr (std::is_same_v<Input, NoInput>) {
    return Problem::none;
  } else if constexpr (std::is_arithmetic_v<Input>) {
    if (!std::isfinite(static_cast<double>(u))) return Problem::non_finite_input;
    if (std::abs(static_cast<double>(u)) > opts.max_abs_input) return Problem::input_magnitude;
    return Problem::none;
  } else if constexpr (std::is_base_of_v<Eigen::DenseBase<Input>, Input>) {
    if (!all_finite(u)) return Problem::non_finite_input;
    if (u.size() > 0 && u.cwiseAbs().maxCoeff() > opts.max_abs_input) return Problem::input_magnitude;
    return Problem::none;
  } else {
    static_assert(requires { { u.is_finite() } -> std::convertible_to<bool>; },
                  "a process input type must be NoInput, arithmetic, an Eigen type, or provide "
                  "bool is_finite() const (and optionally double max_abs() const)");
    if (!u.is_finite()) return Problem::non_finite_input;
    if constexpr (requires { { u.max_abs() } -> std::convertible_to<double>; }) {
      if (u.max_abs() > opts.max_abs_input) return Problem::input_magnitude;
    }
    return Problem::none;
  }
}

/// Process noise must have non-negative variances. A full semi-definiteness test would cost a
/// factorisation per prediction; the propagated covariance is checked instead. NaN or Inf in
/// Q (or F) always reaches F P F' + Q, so the filters test that sum once and call
/// diagnose_non_finite_prediction only on the failure path, to name the culprit.
template <class Derived>
Problem check_process_noise(const Eigen::MatrixBase<Derived>& Q) {
  if ((Q.diagonal().array() < 0.0).any()) return Problem::process_noise_negative_variance;
  return Problem::none;
}

template <class DerivedQ, class DerivedF>
Problem diagnose_non_finite_prediction(const Eigen::MatrixBase<DerivedQ>& Q, const Eigen::MatrixBase<DerivedF>& F) {
  if (!all_finite(Q)) return Problem::process_noise_non_finite;
  if (!all_finite(F)) return Problem::non_finite_prediction;
  return Problem::non_finite_covariance;
}

/// Eigen matrix expressions whose size is known only at run time: a VectorXd, a Map or Ref of
/// one, a segment with run-time extents. The entry points of the filters take fixed-size
/// vectors, to which such an expression converts silently (reading past its end when it is too
/// short: Eigen's size assert is compiled out under NDEBUG). So each entry point has an
/// overload for these that checks the size first and refuses a wrong one with
/// Problem::measurement_wrong_size or Problem::input_wrong_size, in every build mode.
namespace detail {
template <class D>
void matrix_base_of(const Eigen::MatrixBase<D>*);
}  // namespace detail

/// Any Eigen matrix expression, including those whose matrix base is another type's (a
/// VectorBlock derives from MatrixBase<Block<...>>, not MatrixBase<VectorBlock<...>>).
template <class T>
concept EigenMatrixExpression = requires(const T* p) { detail::matrix_base_of(p); };

template <class T>
concept DynamicSizeEigen = EigenMatrixExpression<T> && (T::SizeAtCompileTime == Eigen::Dynamic);

/// A fixed-size Eigen matrix type (the measurement vectors, and the input of most models).
template <class T>
concept FixedSizeEigen = EigenMatrixExpression<T> && (T::SizeAtCompileTime != Eigen::Dynamic);

/// out = v when v has Fixed's rows and columns; otherwise `wrong_size`, and out is untouched.
template <FixedSizeEigen Fixed, DynamicSizeEigen V>
Problem copy_sized(const V& v, Fixed& out, Problem wrong_size) {
  if (v.rows() != Fixed::RowsAtCompileTime || v.cols() != Fixed::ColsAtCompileTime) return wrong_size;
  out = v;
  return Problem::none;
}

/// step(fixed) with v copied into a Fixed when its size is Fixed's; otherwise an invalid-input
/// Status naming `wrong_size`, and step is not called. The entry points' run-time sized overloads.
template <FixedSizeEigen Fixed, DynamicSizeEigen V, class Step>
Status with_size_checked(const V& v, Problem wrong_size, Step&& step) {
  Fixed fixed;
  if (Problem p = copy_sized(v, fixed, wrong_size); p != Problem::none) return Status::invalid(p);
  return step(static_cast<const Fixed&>(fixed));
}

template <int M>
Problem check_measurement(const Vector<M>& z, const SquareMatrix<M>& R, const FilterOptions& opts) {
  if (!all_finite(z)) return Problem::non_finite_measurement;
  if (z.cwiseAbs().maxCoeff() > opts.max_abs_measurement) return Problem::measurement_magnitude;
  if (!all_finite(R)) return Problem::measurement_noise_non_finite;
  if (!is_positive_definite(R)) return Problem::measurement_noise_not_positive_definite;
  return Problem::none;
}

}  // namespace ctxfuse

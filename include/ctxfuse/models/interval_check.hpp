// What a process model whose input is an interval of IMU samples checks of it: that the
// interval covers the step (planar_interval.hpp, planar_preintegration.hpp,
// ins_preintegration.hpp), and, for a preintegrated interval, that it holds samples and
// finite sums.
#pragma once

#include <algorithm>
#include <cmath>

#include "ctxfuse/core/status.hpp"

namespace ctxfuse::models {

/// An interval whose duration is not the step's dt (to `tolerance`, relative) is the caller's
/// error, not motion: dt_above_maximum.
inline Problem check_interval_duration(double duration, double dt, double tolerance) {
  return std::abs(duration - dt) <= tolerance * std::max(1.0, dt) ? Problem::none : Problem::dt_above_maximum;
}

/// The input checks of a process model on a preintegrated interval (an Input with count() and
/// is_finite()); the models derive from it.
struct PreintegratedIntervalCheck {
  /// How far the interval's duration may be from the step's dt (relative).
  double duration_tolerance = 1e-6;

  /// An empty or non-finite interval: non_finite_input.
  template <class Input>
  Problem check_input(const Input& u) const {
    if (u.count() < 1) return Problem::non_finite_input;
    return u.is_finite() ? Problem::none : Problem::non_finite_input;
  }
  /// check_input, and that the interval covers dt.
  template <class Input>
  Problem check(const Input& u, double dt) const {
    if (Problem p = check_input(u); p != Problem::none) return p;
    return check_interval_duration(u.duration(), dt, duration_tolerance);
  }
};

}  // namespace ctxfuse::models

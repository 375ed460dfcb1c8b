// Time keeping for the stateful filter wrappers: turns "predict to time t" into a checked dt.
#pragma once

#include <cmath>
#include <limits>

#include "ctxfuse/core/status.hpp"

namespace ctxfuse {

class FilterClock {
 public:
  bool is_set() const { return std::isfinite(time_); }
  double time() const { return time_; }
  void set(double t) { time_ = t; }

  /// dt from the current time to `t`, or the problem with it. Does not advance the clock.
  Problem dt_to(double t, double& dt) const {
    if (!is_set()) return Problem::time_not_set;
    if (!std::isfinite(t)) return Problem::non_finite_dt;
    if (t < time_) return Problem::out_of_order_time;
    dt = t - time_;
    return Problem::none;
  }

 private:
  double time_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace ctxfuse

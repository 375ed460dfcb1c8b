// The last input a filter accepted, held over the interval of an input it refuses.
// io::replay holds each IMU sample over the interval after its stamp, so the interval of a
// sample that never came is covered by the sample before it. A sample that came but is refused
// (non-finite, absurd rates) is treated the same way: its interval is propagated with the last
// accepted input. Skipping the interval instead loses the motion over it (v dt per step: 12 m
// after 5 s of NaN samples at 2.5 m/s on the region pipeline's drive). region_imm's Aided and
// gins' ForwardPass apply their IMU inputs through this one rule.
#pragma once

#include <optional>

#include "ctxfuse/core/status.hpp"

namespace ctxfuse::models {

/// What went into the filter for one input.
enum class InputUse {
  taken,  // the input itself
  held,   // the input was refused; the last accepted one went in over its interval
  lost,   // the input was refused and there was no accepted one to hold (or it was refused too)
};

template <class Input>
class HeldInput {
 public:
  /// step(x) -> Status applies one input; it is called with `u`, and when that is refused, once
  /// more with the last input accepted. A step that refuses must leave its filter as it was
  /// (every ctxfuse predict does), so the second call starts from the same state.
  template <class Step>
  InputUse apply(const Input& u, Step&& step) {
    if (step(u).accepted()) {
      last_ = u;
      return InputUse::taken;
    }
    if (last_ && step(*last_).accepted()) return InputUse::held;
    return InputUse::lost;
  }

  /// The last input accepted (none before the first).
  const std::optional<Input>& last() const { return last_; }

 private:
  std::optional<Input> last_;
};

}  // namespace ctxfuse::models

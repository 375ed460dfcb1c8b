// models::HeldInput: the rule every IMU-driven pipeline applies to a refused input (the last
// accepted one propagates over its interval). A toy integrator x += u dt that refuses a
// non-finite u stands for the filter; the expected positions are written out by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "ctxfuse/models/held_input.hpp"

namespace {
using namespace ctxfuse;
using models::HeldInput;
using models::InputUse;

struct Integrator {
  double x = 0.0;
  int calls = 0;
  Status step(double u, double dt) {
    ++calls;
    if (!std::isfinite(u)) return Status::invalid(Problem::non_finite_input);
    x += u * dt;
    return Status{};
  }
};

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(HeldInput, RefusedInputIsReplacedByTheLastAccepted) {
  Integrator f;
  HeldInput<double> held;
  std::vector<InputUse> uses;
  for (double u : {2.0, 3.0, kNaN, kNaN, 5.0}) uses.push_back(held.apply(u, [&](double v) { return f.step(v, 0.5); }));
  EXPECT_EQ(uses, (std::vector<InputUse>{InputUse::taken, InputUse::taken, InputUse::held, InputUse::held, InputUse::taken}));
  // 2 and 3 over 0.5 s each, 3 held over the two refused intervals, then 5: 1 + 1.5 + 1.5 + 1.5 + 2.5.
  EXPECT_DOUBLE_EQ(f.x, 8.0);
  // One call per taken input, two per held one (the refusal, then the held input).
  EXPECT_EQ(f.calls, 7);
  ASSERT_TRUE(held.last());
  EXPECT_EQ(*held.last(), 5.0);
}

TEST(HeldInput, NothingToHoldBeforeTheFirstAcceptedInput) {
  Integrator f;
  HeldInput<double> held;
  EXPECT_EQ(held.apply(kNaN, [&](double v) { return f.step(v, 1.0); }), InputUse::lost);
  EXPECT_FALSE(held.last());
  EXPECT_EQ(f.x, 0.0);
  EXPECT_EQ(f.calls, 1);
}

TEST(HeldInput, LostWhenTheHeldInputIsRefusedToo) {
  // A step that refuses on the second interval whatever the input (a filter failure, say):
  // the held input is tried once and the input counts as lost; the last accepted one stays.
  HeldInput<double> held;
  int call = 0;
  auto step = [&](double) { return ++call == 1 ? Status{} : Status::invalid(Problem::non_finite_input); };
  EXPECT_EQ(held.apply(1.0, step), InputUse::taken);
  EXPECT_EQ(held.apply(2.0, step), InputUse::lost);
  EXPECT_EQ(call, 3);
  EXPECT_EQ(*held.last(), 1.0);
}

}  // namespace

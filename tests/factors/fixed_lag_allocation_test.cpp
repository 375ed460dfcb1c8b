// A smoother step never touches the heap: accepted steps with marginalisation, epochs with
// ranges left out, and refused steps (support/heap_counter.hpp counts operator new and
// Eigen's own mallocs).
#include "support/heap_counter.hpp"

#include <gtest/gtest.h>

#include <memory>

#include "ctxfuse/filters/fixed_lag.hpp"
#include "straight_turn.hpp"

namespace {
using namespace ctxfuse;
using test::Cv2;
using test::Range2;
using test::StraightTurnDrive;
using Smoother = FixedLagSmoother<Cv2, Range2, 10, 4>;

TEST(FixedLagAllocation, StepsNeverAllocate) {
  const StraightTurnDrive drive(4, 30.0);
  auto s = std::make_unique<Smoother>(drive.motion());
  Gaussian<4> g;
  g.mean = drive.epochs[0].truth;
  ASSERT_TRUE(s->initialise(0.0, g));
  int accepted = 0, refused = 0;
  const long uses = test::heap_uses([&] {
    for (std::size_t k = 1; k < drive.epochs.size(); ++k) {
      Smoother::Measurements m;
      for (int a = 0; a < 4; ++a)
        m.add(drive.range(a), Vector<1>(drive.epochs[k].ranges[static_cast<std::size_t>(a)]), (k + a) % 5 != 0);
      accepted += s->step(drive.epochs[k].t, {}, m).accepted();
      refused += !s->step(drive.epochs[k].t, {}, m).accepted();  // same time again: refused
      (void)s->newest_belief();
    }
  });
  EXPECT_EQ(uses, 0);
  EXPECT_EQ(accepted, static_cast<int>(drive.epochs.size()) - 1);
  EXPECT_EQ(refused, accepted);
  EXPECT_EQ(s->window().size, 10);
}

}  // namespace

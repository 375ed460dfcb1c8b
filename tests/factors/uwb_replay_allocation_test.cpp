// Ten minutes of UWB epochs (6000) through the pipeline's fixed-lag smoother never touch the
// heap (support/heap_counter.hpp counts operator new and Eigen's own mallocs), and the
// estimate stays on the circle: the window slides, marginalises and keeps going.
#include "support/heap_counter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "uwb_replay.hpp"

namespace {
using namespace ctxfuse;
namespace nu = pipelines::nlos_uwb;

TEST(UwbReplayAllocation, TenMinutesThroughTheSmootherNeverAllocate) {
  const test::UwbReplay replay(10);
  auto s = std::make_unique<nu::RangeSmoother<>>(nu::Settings{});
  ASSERT_TRUE(s->start(0.0, replay.start_position(), replay.start_cov()).accepted());
  int refused = 0;
  double worst = 0.0;
  const long uses = test::heap_uses([&] {
    for (std::size_t k = 0; k < replay.epochs.size(); ++k) {
      refused += !replay.step(*s, k);
      worst = std::max(worst, std::abs(s->position().norm() - test::UwbReplay::radius));
    }
  });
  EXPECT_EQ(uses, 0);
  EXPECT_EQ(refused, 0);
  EXPECT_EQ(s->smoother().window().size, 10);
  EXPECT_DOUBLE_EQ(s->time(), 600.0);
  EXPECT_LT(worst, 0.5);  // 5 range sigmas: the estimate never leaves the circle
}

}  // namespace

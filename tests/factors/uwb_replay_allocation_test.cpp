// Ten minutes of UWB epochs (6000) through the pipeline's fixed-lag smoother never touch the
// heap (support/heap_counter.hpp counts operator new and Eigen's own mallocs), and the
// estimate stays on the circle: the window slides, marginalises and keeps going.
#include "support/heap_counter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "ctxfuse/pipelines/nlos_uwb/imu_smoother.hpp"
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

// The same replay with IMU factors: the circle's IMU (yaw rate v / r, centripetal v^2 / r to
// the left) at 100 Hz handed to the smoother piece by piece, the start by alignment from the
// true positions of the first two seconds.
TEST(UwbReplayAllocation, TenMinutesThroughTheImuSmootherNeverAllocate) {
  const test::UwbReplay replay(10);
  auto s = std::make_unique<nu::ImuRangeSmoother<>>(nu::Settings{}, nu::ImuFusionSettings{});
  std::size_t k = replay.align(*s);
  ASSERT_TRUE(s->started());
  const std::size_t first = k;
  int refused = 0;
  double worst = 0.0, imu_t = s->time();
  const long uses = test::heap_uses([&] {
    for (; k < replay.epochs.size(); ++k) {
      replay.feed_imu(*s, k, imu_t);
      refused += !replay.step(*s, k);
      worst = std::max(worst, std::abs(s->position().norm() - test::UwbReplay::radius));
    }
  });
  EXPECT_EQ(uses, 0);
  EXPECT_EQ(refused, 0);
  EXPECT_GT(first, 10u);  // ~1.7 s of fixes before 5 m of baseline
  EXPECT_EQ(s->smoother().window().size, 10);
  EXPECT_DOUBLE_EQ(s->time(), 600.0);
  EXPECT_LT(worst, 0.5);
}

}  // namespace

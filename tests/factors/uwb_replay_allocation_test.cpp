// Ten minutes of UWB epochs (6000) through the pipeline's fixed-lag smoother never touch the
// heap (support/heap_counter.hpp counts operator new and Eigen's own mallocs), and the
// estimate stays on the circle: the window slides, marginalises and keeps going. The EKF of the
// same IMU fusion neither.
#include "support/heap_counter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "ctxfuse/pipelines/nlos_uwb/calibrated_ekf.hpp"
#include "ctxfuse/pipelines/nlos_uwb/imu_ekf.hpp"
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

// The self-calibrating EKF with its fixed-lag output (the ring of update records wraps every
// few seconds) over the same replay, whose ranges are raw (one sample per report); the lagged
// output is asked for every epoch, as the run loop does.
TEST(UwbReplayAllocation, TenMinutesThroughTheCalibratedEkfAndItsLaggedOutputNeverAllocate) {
  const test::UwbReplay replay(10);
  const nu::Settings settings = test::UwbReplay::settings();
  auto s = std::make_unique<nu::CalibratedRangeEkf<policies::ChiSquareGate, true>>(settings);
  ASSERT_TRUE(s->start(0.0, replay.start_position(), replay.start_cov()).accepted());
  int refused = 0;
  double worst = 0.0, worst_lagged = 0.0, lag_min = 1e9, lag_max = 0.0;
  const long uses = test::heap_uses([&] {
    for (std::size_t k = 0; k < replay.epochs.size(); ++k) {
      refused += !replay.step(*s, k);
      worst = std::max(worst, std::abs(s->position().norm() - test::UwbReplay::radius));
      worst_lagged = std::max(worst_lagged, std::abs(s->output_position().norm() - test::UwbReplay::radius));
      if (k > 20) {
        lag_min = std::min(lag_min, s->time() - s->output_time());
        lag_max = std::max(lag_max, s->time() - s->output_time());
      }
    }
  });
  EXPECT_EQ(uses, 0);
  EXPECT_EQ(refused, 0);
  EXPECT_DOUBLE_EQ(s->time(), 600.0);
  EXPECT_LT(worst, 0.5);
  EXPECT_LT(worst_lagged, 0.5);
  // One record per epoch here (the replay's four ranges share a stamp): exactly the lag back.
  EXPECT_NEAR(lag_min, settings.smoothed_output_lag_s, 1e-6);
  EXPECT_NEAR(lag_max, settings.smoothed_output_lag_s, 1e-6);
}

// The replay through an estimator that takes the IMU: the circle's IMU (yaw rate v / r,
// centripetal v^2 / r to the left) at 100 Hz handed over piece by piece, the start by
// alignment from the true positions of the first two seconds. Heap uses, refused steps, the
// first epoch after the start and the worst distance from the circle.
struct ImuReplayRun {
  long heap_uses = -1;
  int refused = 0;
  std::size_t first = 0;
  double worst = 0.0;
};
template <class Estimator>
ImuReplayRun run_with_imu(Estimator& s, const test::UwbReplay& replay) {
  ImuReplayRun out;
  std::size_t k = replay.align(s);
  if (!s.started()) return out;
  out.first = k;
  double imu_t = s.time();
  out.heap_uses = test::heap_uses([&] {
    for (; k < replay.epochs.size(); ++k) {
      replay.feed_imu(s, k, imu_t);
      out.refused += !replay.step(s, k);
      out.worst = std::max(out.worst, std::abs(s.position().norm() - test::UwbReplay::radius));
    }
  });
  return out;
}

TEST(UwbReplayAllocation, TenMinutesThroughTheImuSmootherNeverAllocate) {
  const test::UwbReplay replay(10);
  auto s = std::make_unique<nu::ImuRangeSmoother<>>(nu::Settings{}, nu::ImuFusionSettings{});
  const ImuReplayRun r = run_with_imu(*s, replay);
  ASSERT_TRUE(s->started());
  EXPECT_EQ(r.heap_uses, 0);
  EXPECT_EQ(r.refused, 0);
  EXPECT_GT(r.first, 10u);  // ~1.7 s of fixes before 5 m of baseline
  EXPECT_EQ(s->smoother().window().size, 10);
  EXPECT_DOUBLE_EQ(s->time(), 600.0);
  EXPECT_LT(r.worst, 0.5);
}

// The EKF with the IMU over the same replay: one interval prediction per attached range.
TEST(UwbReplayAllocation, TenMinutesThroughTheImuEkfNeverAllocate) {
  const test::UwbReplay replay(10);
  auto s = std::make_unique<nu::ImuRangeEkf<>>(nu::Settings{}, nu::ImuFusionSettings{});
  const ImuReplayRun r = run_with_imu(*s, replay);
  ASSERT_TRUE(s->started());
  EXPECT_EQ(r.heap_uses, 0);
  EXPECT_EQ(r.refused, 0);
  EXPECT_DOUBLE_EQ(s->time(), 600.0);
  EXPECT_LT(r.worst, 0.5);
}

}  // namespace

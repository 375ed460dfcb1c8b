// The region pipeline's aided-filter wrapper (pipelines/region_imm/aided.hpp) on refused inputs,
// for each of its cores (one EKF, the federated filter, the IMM):
//  - a refused IMU sample (NaN, Inf, absurd rate) is replaced by the last accepted one over its
//    interval, as the replay does for a dropped sample: the belief afterwards is bit for bit
//    the one of the same run with that sample replaced by its predecessor, and the refusal is
//    counted (Track::rejected_imu). Skipping the interval instead (the behaviour before) leaves
//    the belief behind the motion by v dt per refused step.
//  - the vehicle constraint's outcome is no longer dropped: a NaN speed under the speed update
//    is refused, counted (Track::rejected_speed), and the belief stays as it was; an accepted
//    one is not counted.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "ctxfuse/pipelines/region_imm/estimators.hpp"
#include "ctxfuse/instances/region_imm.hpp"  // region_imm::run compiled once (ctxfuse::instances)
#include "ctxfuse/pipelines/region_imm/run.hpp"

namespace {
using namespace ctxfuse;
namespace ri = pipelines::region_imm;
using ri::L;
using Mixing = policies::FixedTransition<3>;

Gaussian<L::size> start_belief() {
  Gaussian<L::size> b;
  b.mean.setZero();
  L::get<"v">(b.mean) = Vector<2>(5.0, 0.0);
  Vector<L::size> sd;
  sd << 1.0, 1.0, 0.2, 0.2, 0.05, 1e-3, 0.05, 0.05;
  b.cov = sd.cwiseAbs2().asDiagonal();
  return b;
}

models::PlanarImu input(int k) {
  models::PlanarImu u;
  u.yaw_rate = 0.1 + 0.01 * k;
  u.accel = Vector<2>(0.3 - 0.02 * k, 0.5);
  return u;
}

// One belief of each core, to compare bit for bit.
Gaussian<L::size> belief_of(const ri::SingleCore& c) { return c.f->belief(); }
Gaussian<L::size> belief_of(const ri::FederatedCore& c) { return c.f->global(); }
Gaussian<L::size> belief_of(const ri::ImmCore<Mixing>& c) { return c.f->combined(); }

void expect_same(const Gaussian<L::size>& a, const Gaussian<L::size>& b) {
  for (int i = 0; i < L::size; ++i) {
    EXPECT_EQ(a.mean(i), b.mean(i)) << i;
    for (int j = 0; j < L::size; ++j) EXPECT_EQ(a.cov(i, j), b.cov(i, j)) << i << "," << j;
  }
}

template <class Core>
struct Harness {
  ri::Settings s;
  std::optional<ri::Aided<Core>> a;

  explicit Harness(bool use_speed) {
    s.use_speed = use_speed;
    a.emplace(make(), s);
    a->start(0.0, start_belief());
  }
  Core make() {
    if constexpr (std::is_same_v<Core, ri::SingleCore>) return Core{&s, true, false, 1.0, 1.0};
    else if constexpr (std::is_same_v<Core, ri::FederatedCore>) return Core{&s};
    else return Core{&s, ri::detail::make_mixing<Mixing>(s), nullptr};
  }
  /// Ten IMU steps of 10 ms; step `k_bad` gets `bad` (or, when `hold`, the step before's input).
  void drive(int k_bad, const models::PlanarImu& bad, bool hold) {
    for (int k = 0; k < 10; ++k) a->predict(k != k_bad ? input(k) : hold ? input(k - 1) : bad, 0.01);
  }
};

template <class Core>
void refused_imu_sample_is_held(const models::PlanarImu& bad) {
  Harness<Core> faulted(false), held(false);
  faulted.drive(5, bad, false);
  held.drive(5, bad, true);
  EXPECT_EQ(faulted.a->track().rejected_imu, 1u);
  EXPECT_EQ(held.a->track().rejected_imu, 0u);
  expect_same(belief_of(faulted.a->core()), belief_of(held.a->core()));
}

template <class Core>
void refused_imu_samples() {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  models::PlanarImu u = input(5);
  u.yaw_rate = nan;
  refused_imu_sample_is_held<Core>(u);
  u = input(5);
  u.accel(1) = inf;
  refused_imu_sample_is_held<Core>(u);
  u = input(5);
  u.yaw_rate = 50.0;  // above PlanarImuModel::max_yaw_rate: a broken sample, not a car
  refused_imu_sample_is_held<Core>(u);
}

TEST(AidedInput, RefusedImuSampleIsReplacedByThePreviousOneSingle) { refused_imu_samples<ri::SingleCore>(); }
TEST(AidedInput, RefusedImuSampleIsReplacedByThePreviousOneFederated) { refused_imu_samples<ri::FederatedCore>(); }
TEST(AidedInput, RefusedImuSampleIsReplacedByThePreviousOneImm) { refused_imu_samples<ri::ImmCore<Mixing>>(); }

template <class Core>
void speed_status_is_counted() {
  Harness<Core> h(true);
  h.drive(-1, {}, false);
  const Gaussian<L::size> before = belief_of(h.a->core());
  h.a->speed(messages::SpeedSample{0.1, std::numeric_limits<double>::quiet_NaN()});
  EXPECT_EQ(h.a->track().rejected_speed, 1u);
  expect_same(belief_of(h.a->core()), before);
  const double speed = L::get<"v">(before.mean).norm();
  h.a->speed(messages::SpeedSample{0.1, speed});
  EXPECT_EQ(h.a->track().rejected_speed, 1u);
  // The NHC (the default, use_speed false) does not read the value: a NaN speed is accepted.
  Harness<Core> nhc(false);
  nhc.a->speed(messages::SpeedSample{0.0, std::numeric_limits<double>::quiet_NaN()});
  EXPECT_EQ(nhc.a->track().rejected_speed, 0u);
}

TEST(AidedInput, RefusedSpeedIsCountedSingle) { speed_status_is_counted<ri::SingleCore>(); }
TEST(AidedInput, RefusedSpeedIsCountedFederated) { speed_status_is_counted<ri::FederatedCore>(); }
TEST(AidedInput, RefusedSpeedIsCountedImm) { speed_status_is_counted<ri::ImmCore<Mixing>>(); }

}  // namespace

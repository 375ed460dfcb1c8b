// The smoother's step time over a 10-minute replay (issue 16: "flat over a 10-minute replay"):
// tests/factors/uwb_replay.hpp's 6000 epochs (4 ranges, every 7th left out) through the
// pipeline's fixed-lag smoother (pipelines/nlos_uwb/smoother.hpp: K = 10, gate, 16 slots),
// and through the pipeline's EKFs.
// One iteration is the whole replay from a fresh start; the counters are the mean step time of
// each minute (this thread's CPU clock around the minute's 600 steps, summed over iterations:
// the shared machine's load inflates wall time) and the ratio of the last minute's to the
// first's. Run with
//   bench_fixed_lag --benchmark_filter=Replay --benchmark_repetitions=5
//                   --benchmark_out=replay.json --benchmark_out_format=json
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <ctime>
#include <memory>
#include <string>

#include "ctxfuse/pipelines/nlos_uwb/calibrated_ekf.hpp"
#include "ctxfuse/pipelines/nlos_uwb/imu_ekf.hpp"
#include "ctxfuse/pipelines/nlos_uwb/imu_smoother.hpp"
#include "uwb_replay.hpp"

namespace {
using namespace ctxfuse;
namespace nu = pipelines::nlos_uwb;

double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

template <class Estimator>
void FixedLag_Replay10min(benchmark::State& state) {
  const test::UwbReplay replay(10);
  constexpr int kMinutes = 10;
  std::array<double, kMinutes> minute_s{};
  auto s = std::make_unique<Estimator>(test::UwbReplay::settings());
  int refused = 0;
  for (auto _ : state) {
    state.PauseTiming();
    *s = Estimator(test::UwbReplay::settings());
    (void)s->start(0.0, replay.start_position(), replay.start_cov());
    state.ResumeTiming();
    for (int m = 0; m < kMinutes; ++m) {
      const double t0 = thread_cpu_s();
      for (int i = 0; i < test::UwbReplay::epochs_per_minute; ++i) {
        refused += !replay.step(*s, static_cast<std::size_t>(m * test::UwbReplay::epochs_per_minute + i));
        // A fixed-lag output is asked for every epoch, as the run loop does.
        if constexpr (requires { s->output_position(); }) benchmark::DoNotOptimize(s->output_position().data());
      }
      minute_s[static_cast<std::size_t>(m)] += thread_cpu_s() - t0;
    }
    benchmark::DoNotOptimize(s->position().data());
  }
  if (refused > 0) state.SkipWithError("a step was refused");
  const double steps = static_cast<double>(state.iterations()) * test::UwbReplay::epochs_per_minute;
  for (int m = 0; m < kMinutes; ++m)
    state.counters["step_us_min" + std::to_string(m + 1)] = 1e6 * minute_s[static_cast<std::size_t>(m)] / steps;
  state.counters["last_over_first"] = minute_s[kMinutes - 1] / minute_s[0];
  state.counters["steps_per_replay"] = kMinutes * test::UwbReplay::epochs_per_minute;
}

// The same replay through the smoother with IMU factors (imu_smoother.hpp: the 8-state planar
// IMU state, one IMU factor of ~10 samples per interval), and through the EKF of the same
// fusion (imu_ekf.hpp: one interval prediction and one scalar update per attached range),
// each started by alignment outside the timing; the IMU pieces are handed over inside it, as
// the run loop does.
template <class Smoother>
void FixedLag_ImuReplay10min(benchmark::State& state) {
  const test::UwbReplay replay(10);
  constexpr int kMinutes = 10;
  std::array<double, kMinutes> minute_s{};
  auto s = std::make_unique<Smoother>(nu::Settings{}, nu::ImuFusionSettings{});
  int refused = 0;
  std::size_t first = 0;
  for (auto _ : state) {
    state.PauseTiming();
    *s = Smoother(nu::Settings{}, nu::ImuFusionSettings{});
    first = replay.align(*s);
    double imu_t = s->time();
    state.ResumeTiming();
    for (std::size_t k = first; k < replay.epochs.size(); ++k) {
      const double t0 = thread_cpu_s();
      replay.feed_imu(*s, k, imu_t);
      refused += !replay.step(*s, k);
      minute_s[std::min<std::size_t>(k / test::UwbReplay::epochs_per_minute, kMinutes - 1)] += thread_cpu_s() - t0;
    }
    benchmark::DoNotOptimize(s->position().data());
  }
  if (first == replay.epochs.size()) state.SkipWithError("the alignment never completed");
  if (refused > 0) state.SkipWithError("a step was refused");
  const double iters = static_cast<double>(state.iterations());
  for (int m = 0; m < kMinutes; ++m) {
    const double n = m == 0 ? static_cast<double>(test::UwbReplay::epochs_per_minute - first) : test::UwbReplay::epochs_per_minute;
    state.counters["step_us_min" + std::to_string(m + 1)] = 1e6 * minute_s[static_cast<std::size_t>(m)] / (iters * n);
  }
  state.counters["last_over_first"] = (minute_s[kMinutes - 1] / test::UwbReplay::epochs_per_minute) /
                                      (minute_s[0] / static_cast<double>(test::UwbReplay::epochs_per_minute - first));
  state.counters["steps_per_replay"] = static_cast<double>(replay.epochs.size() - first);
}

BENCHMARK(FixedLag_Replay10min<nu::RangeSmoother<>>)->Name("FixedLag/Replay10min")->Unit(benchmark::kMillisecond);
// The constant-velocity EKFs of the same fusion: plain (estimators.hpp), self-calibrating
// (calibrated_ekf.hpp: 8 anchor-bias slots), and the latter with its 0.9 s fixed-lag output.
BENCHMARK(FixedLag_Replay10min<nu::RangeEkf<>>)->Name("FixedLag/EkfReplay10min")->Unit(benchmark::kMillisecond);
BENCHMARK(FixedLag_Replay10min<nu::CalibratedRangeEkf<>>)->Name("FixedLag/CalibratedEkfReplay10min")->Unit(benchmark::kMillisecond);
BENCHMARK(FixedLag_Replay10min<nu::CalibratedRangeEkf<policies::ChiSquareGate, true>>)
    ->Name("FixedLag/CalibratedEkfLagReplay10min")
    ->Unit(benchmark::kMillisecond);
BENCHMARK(FixedLag_ImuReplay10min<nu::ImuRangeSmoother<>>)->Name("FixedLag/ImuReplay10min")->Unit(benchmark::kMillisecond);
BENCHMARK(FixedLag_ImuReplay10min<nu::ImuRangeEkf<>>)->Name("FixedLag/ImuEkfReplay10min")->Unit(benchmark::kMillisecond);

}  // namespace

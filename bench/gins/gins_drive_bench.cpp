// The whole real drive's forward pass (issue 17): ctxfuse::pipelines::gins::run<Nav20> over
// $CTXFUSE_DATA_DIR/gnss-imu-drive (default: the CTXFUSE_DATA_DIR of the CMake configure) with
// what docs/results.md "gins_real" runs there: the drive's installation, ZUPT + NHC, 15 s
// outages every 45 s from 40 s, GNSS at 1 Hz; forward only (no RTS pass; the step records the
// smoother would need are stored, as run() always does).
//   Gins/Drive/ReadAndForward   read_recording + run, per iteration
//   Gins/Drive/Forward          run on the recording read once before the timed loop
//   Gins/Drive/Read             read_recording alone (the reading's share, measured directly)
// Counters, per CPU second: imu_epochs_per_s and s_per_imu_epoch (over the recording's IMU
// sample count), realtime_factor (recording seconds, first to last IMU sample, per second).
// One iteration is a whole drive (about half a second), so each benchmark runs 1 iteration x
// 5 repetitions (1 under CTXFUSE_BENCH_SMOKE, which scripts/bench_smoke.sh sets). Without the
// data folder both report an error (SkipWithError) instead of a time. Run with
//   bench_gins_drive --benchmark_out=bench_gins_drive.json --benchmark_out_format=json
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>

#include "ctxfuse/studies/gins_outages.hpp"
#include "ctxfuse/instances/gins_nav20.hpp"

#ifndef CTXFUSE_BENCH_DATA_DIR
#define CTXFUSE_BENCH_DATA_DIR "../shared/data"
#endif

namespace {
namespace gins = ctxfuse::pipelines::gins;

std::filesystem::path drive_dir() {
  const char* env = std::getenv("CTXFUSE_DATA_DIR");
  const std::filesystem::path root = env != nullptr && *env != '\0' ? env : CTXFUSE_BENCH_DATA_DIR;
  return root / "gnss-imu-drive";
}

gins::RunOptions drive_options() {
  gins::RunOptions o;
  o.installation = ctxfuse::studies::gnss_imu_drive_installation();
  o.constraints.zupt = o.constraints.nhc = true;
  o.outages = ctxfuse::studies::standard_outages();
  o.gnss_rate_hz = ctxfuse::studies::kStandardGnssRateHz;
  return o;
}

// The recording, read once, and one untimed run that must align and score the outages (so a
// benchmark never times a pass that failed); error is empty when both worked.
struct Drive {
  gins::Recording rec;
  std::string error;
  double duration_s = 0.0;  // first to last IMU sample
  double forward_rms_m = 0.0, forward_max_m = 0.0;
};

const Drive& drive() {
  static const Drive d = [] {
    Drive r;
    const std::filesystem::path dir = drive_dir();
    if (!std::filesystem::is_directory(dir)) {
      r.error = "recording not found: " + dir.string() + " (set CTXFUSE_DATA_DIR to the shared/data folder)";
      return r;
    }
    try {
      r.rec = gins::read_recording(dir);
    } catch (const std::exception& e) {
      r.error = std::string("cannot read the recording: ") + e.what();
      return r;
    }
    if (r.rec.imu.size() < 2 || r.rec.fixes.empty()) {
      r.error = dir.string() + ": no IMU samples or no fixes";
      return r;
    }
    r.duration_s = r.rec.imu.back().t - r.rec.imu.front().t;
    const gins::RunResult res = gins::run<gins::Nav20>(r.rec.imu, r.rec.fixes, gins::Settings{}, drive_options());
    if (!res.aligned) {
      r.error = "the forward pass never aligned on " + dir.string();
      return r;
    }
    const auto sc = ctxfuse::studies::score_outages(r.rec.fixes, res);
    r.forward_rms_m = sc.forward.rms;
    r.forward_max_m = sc.forward.max;
    return r;
  }();
  return d;
}

void set_counters(benchmark::State& state, const Drive& d) {
  const double n = static_cast<double>(d.rec.imu.size());
  state.counters["imu_epochs"] = n;
  state.counters["recording_s"] = d.duration_s;
  state.counters["imu_epochs_per_s"] = benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["s_per_imu_epoch"] =
      benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["realtime_factor"] = benchmark::Counter(d.duration_s, benchmark::Counter::kIsIterationInvariantRate);
  // The untimed run's outage score: shows the timed configuration is the gins_real one.
  state.counters["forward_rms_m"] = d.forward_rms_m;
  state.counters["forward_max_m"] = d.forward_max_m;
}

// One benchmark: an error instead of a time when the drive is unusable, else body() timed.
template <class Body>
void timed(benchmark::State& state, Body body) {
  const Drive& d = drive();
  if (!d.error.empty()) {
    state.SkipWithError(d.error.c_str());
    return;
  }
  for (auto _ : state) {
    body(d);
    benchmark::ClobberMemory();
  }
  set_counters(state, d);
}

void Drive_ReadAndForward(benchmark::State& state) {
  const gins::RunOptions opt = drive_options();
  timed(state, [&](const Drive&) {
    const gins::Recording rec = gins::read_recording(drive_dir());
    const gins::RunResult res = gins::run<gins::Nav20>(rec.imu, rec.fixes, gins::Settings{}, opt);
    benchmark::DoNotOptimize(res.forward.data());
  });
}

void Drive_Forward(benchmark::State& state) {
  const gins::RunOptions opt = drive_options();
  timed(state, [&](const Drive& d) {
    const gins::RunResult res = gins::run<gins::Nav20>(d.rec.imu, d.rec.fixes, gins::Settings{}, opt);
    benchmark::DoNotOptimize(res.forward.data());
  });
}

void Drive_Read(benchmark::State& state) {
  timed(state, [](const Drive&) {
    const gins::Recording rec = gins::read_recording(drive_dir());
    benchmark::DoNotOptimize(rec.imu.data());
  });
}

int repetitions() { return std::getenv("CTXFUSE_BENCH_SMOKE") != nullptr ? 1 : 5; }

}  // namespace

BENCHMARK(Drive_ReadAndForward)->Name("Gins/Drive/ReadAndForward")->Iterations(1)->Repetitions(repetitions())->Unit(benchmark::kMillisecond);
BENCHMARK(Drive_Forward)->Name("Gins/Drive/Forward")->Iterations(1)->Repetitions(repetitions())->Unit(benchmark::kMillisecond);
BENCHMARK(Drive_Read)->Name("Gins/Drive/Read")->Iterations(1)->Repetitions(repetitions())->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();

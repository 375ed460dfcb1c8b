// Geodetic GNSS/INS steps (issue 17), gins_variants.hpp says how each variant is written:
//   Gins/Propagate15/Engine, /HandWritten   one IMU propagation step, 15 states
//   Gins/Propagate20/Engine, /HandWritten   the same with 5 constant extra states (mount, lever)
//   Gins/GnssUpdate15                       one GNSS position update (lever arm, chi-square
//                                           gate; the 15 x 15 prior copied in each iteration)
//   Gins/RtsBackwardStep15                  one RTS backward step (a 500-epoch record smoothed
//                                           per iteration, time reported per epoch)
// Run with
//   bench_gins --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//       --benchmark_out=bench_gins.json --benchmark_out_format=json
#include <benchmark/benchmark.h>

#include "ctxfuse/filters/rts.hpp"
#include "ctxfuse/models/ins_updates.hpp"
#include "ctxfuse/policies/gating.hpp"
#include "gins_variants.hpp"

namespace {
using namespace gins_bench;

template <class Model>
void engine_propagate(benchmark::State& state, const Model& model) {
  static const bool agree = variants_agree(model);
  if (!agree) {
    state.SkipWithError("engine and hand-written propagation disagree: the comparison would be meaningless");
    return;
  }
  eskf::Belief<Model> b = engine_start<Model>();
  int i = 0;
  for (auto _ : state) {
    const Status s = eskf::predict(model, b, inputs().imu[static_cast<std::size_t>(i++ & 63)], kDt);
    benchmark::DoNotOptimize(s);
    benchmark::ClobberMemory();
    if ((i & 1023) == 0) b = engine_start<Model>();  // keep P at the magnitudes of a real run
  }
}

template <int N, class Model>
void hand_propagate(benchmark::State& state, const Model& model) {
  static const bool agree = variants_agree(model);
  if (!agree) {
    state.SkipWithError("engine and hand-written propagation disagree: the comparison would be meaningless");
    return;
  }
  HandWritten<N> h;
  int i = 0;
  for (auto _ : state) {
    h.step(inputs().imu[static_cast<std::size_t>(i++ & 63)], kDt);
    benchmark::DoNotOptimize(h.P.data());
    benchmark::ClobberMemory();
    if ((i & 1023) == 0) h = HandWritten<N>();
  }
}

void Propagate15_Engine(benchmark::State& s) { engine_propagate(s, make_nav15()); }
void Propagate15_HandWritten(benchmark::State& s) { hand_propagate<15>(s, make_nav15()); }
void Propagate20_Engine(benchmark::State& s) { engine_propagate(s, make_nav20()); }
void Propagate20_HandWritten(benchmark::State& s) { hand_propagate<20>(s, make_nav20()); }

void GnssUpdate15(benchmark::State& state) {
  const Nav15 model = make_nav15();
  const eskf::Belief<Nav15> prior = engine_start<Nav15>();
  models::GnssGeodeticPosition<models::NavState> gnss;
  gnss.lever_arm = Eigen::Vector3d(0.3, -0.1, -1.2);
  gnss.R = models::geodetic_position_noise(prior.nominal.get<"p">(), Eigen::Vector3d(4.0, 4.0, 9.0).asDiagonal());
  const policies::ChiSquareGate gate(0.999);
  const Vector<3> z = earth::GeodeticRetraction::inject(gnss.predict(prior.nominal, nullptr), Eigen::Vector3d(1.5, -2.0, 0.8));
  {
    eskf::Belief<Nav15> b = prior;
    if (!eskf::update(model, gnss, b, z, gate).accepted()) {
      state.SkipWithError("the benchmark's fix is not accepted");
      return;
    }
  }
  for (auto _ : state) {
    eskf::Belief<Nav15> b = prior;
    const Status s = eskf::update(model, gnss, b, z, gate);
    benchmark::DoNotOptimize(s);
    benchmark::DoNotOptimize(b.cov.data());
    benchmark::ClobberMemory();
  }
}

// 500 epochs of 10 IMU steps and one GNSS fix each, recorded as a pipeline records them.
RtsRecorder<Nav15> recorded_run(int epochs) {
  const Nav15 model = make_nav15();
  eskf::Belief<Nav15> b = engine_start<Nav15>();
  RtsRecorder<Nav15> rec;
  rec.reserve(static_cast<std::size_t>(epochs) + 1);
  rec.start(0.0, b);
  models::GnssGeodeticPosition<models::NavState> gnss;
  const policies::ChiSquareGate gate(0.999);
  int k = 0;
  for (int e = 1; e <= epochs; ++e) {
    for (int j = 0; j < 10; ++j, ++k) {
      SquareMatrix<15> F;
      (void)eskf::predict(model, b, inputs().imu[static_cast<std::size_t>(k & 63)], kDt, {}, &F);
      rec.predicted(F);
    }
    const eskf::Belief<Nav15> prior = b;
    gnss.R = models::geodetic_position_noise(b.nominal.get<"p">(), Eigen::Matrix3d::Identity() * 4.0);
    const Vector<3> z = earth::GeodeticRetraction::inject(gnss.predict(b.nominal, nullptr),
                                                          Eigen::Vector3d(std::sin(0.7 * e), std::cos(0.3 * e), 0.5));
    (void)eskf::update(model, gnss, b, z, gate);
    (void)rec.record(0.1 * e, prior, b);
  }
  return rec;
}

void RtsBackwardStep15(benchmark::State& state) {
  constexpr int kEpochs = 500;
  const Nav15 model = make_nav15();
  const RtsRecorder<Nav15> recorded = recorded_run(kEpochs);
  {
    RtsRecorder<Nav15> r = recorded;
    if (!r.smooth(model).accepted()) {
      state.SkipWithError("the smoother refused the recorded run");
      return;
    }
  }
  for (auto _ : state) {
    state.PauseTiming();
    RtsRecorder<Nav15> r = recorded;
    state.ResumeTiming();
    const Status s = r.smooth(model);
    benchmark::DoNotOptimize(s);
    benchmark::ClobberMemory();
  }
  // Seconds per backward step (epoch).
  state.counters["per_step"] = benchmark::Counter(kEpochs, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["record_bytes"] = static_cast<double>(recorded.memory_bytes()) / (kEpochs + 1);
}

}  // namespace

// Interleaved repetitions spread machine noise over the variants alike.
BENCHMARK(Propagate15_Engine)->Name("Gins/Propagate15/Engine")->Repetitions(5);
BENCHMARK(Propagate15_HandWritten)->Name("Gins/Propagate15/HandWritten")->Repetitions(5);
BENCHMARK(Propagate20_Engine)->Name("Gins/Propagate20/Engine")->Repetitions(5);
BENCHMARK(Propagate20_HandWritten)->Name("Gins/Propagate20/HandWritten")->Repetitions(5);
BENCHMARK(GnssUpdate15)->Name("Gins/GnssUpdate15")->Repetitions(5);
BENCHMARK(RtsBackwardStep15)->Name("Gins/RtsBackwardStep15")->Repetitions(5)->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();

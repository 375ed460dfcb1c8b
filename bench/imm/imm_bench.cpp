// One IMM step with three 15-state error-state modes (Ins15Model; GNSS position + one UWB
// range each), against three independent ESKF steps doing the same predictions and updates:
// the ratio is what mixing, scoring, the probability update and the combination cost.
// Run: bench_imm --benchmark_out=imm.json --benchmark_out_format=json
// Instruction counts of the same workloads: bench_imm_steps (see imm_steps.cpp).
#include <benchmark/benchmark.h>

#include "imm_variants.hpp"

namespace {
using namespace imm_bench;

const auto keep = [](auto&& value) { benchmark::DoNotOptimize(value); };

void BM_ImmStep3Eskf15(benchmark::State& state) {
  Setup s;
  auto f = make_imm(s);
  double t = 0.0;
  for (auto _ : state) imm_step(f, s, t, keep);
}
BENCHMARK(BM_ImmStep3Eskf15);

void BM_ThreeIndependentEskf15(benchmark::State& state) {
  Setup s;
  ThreeEskf e(s);
  double t = 0.0;
  for (auto _ : state) three_eskf_step(e, s, t, keep);
}
BENCHMARK(BM_ThreeIndependentEskf15);

}  // namespace

BENCHMARK_MAIN();

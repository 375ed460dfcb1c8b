// ZeroOverhead/{Engine,HandWritten,Dynamic}: one predict + update of the same 15-state ESKF
// written three ways (zero_overhead_variants.hpp says how each is written). Run with
//   bench_zero_overhead --benchmark_out=zero_overhead.json --benchmark_out_format=json
#include <benchmark/benchmark.h>

#include "zero_overhead_variants.hpp"

namespace {
using namespace zero_overhead;

template <class Filter>
void run(benchmark::State& state) {
  static const bool agree = variants_agree();
  if (!agree) {
    state.SkipWithError("the three variants disagree: the comparison would be meaningless");
    return;
  }
  Filter f;
  int i = 0;
  for (auto _ : state) {
    f.step(i++);
    benchmark::ClobberMemory();
  }
  state.counters["steps"] = static_cast<double>(i);
}

void ZeroOverhead_Engine(benchmark::State& s) { run<EngineFilter>(s); }
void ZeroOverhead_HandWritten(benchmark::State& s) { run<HandWrittenFilter>(s); }
void ZeroOverhead_Dynamic(benchmark::State& s) { run<DynamicFilter>(s); }

}  // namespace

// Interleaved repetitions spread machine noise over all three variants alike.
BENCHMARK(ZeroOverhead_Engine)->Name("ZeroOverhead/Engine")->Repetitions(5);
BENCHMARK(ZeroOverhead_HandWritten)->Name("ZeroOverhead/HandWritten")->Repetitions(5);
BENCHMARK(ZeroOverhead_Dynamic)->Name("ZeroOverhead/Dynamic")->Repetitions(5);
BENCHMARK_MAIN();

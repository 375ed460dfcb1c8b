// SvmPredictProbability/Ours vs /LibSvm: the same libsvm model file, loaded by libsvm and by our
// loader, the same inputs; /Fast is ours with the fast Gauss transform (svm_fast_rbf.hpp: the
// target grid inside the data, the source boxes outside), /FastBoxes the same with the source
// boxes only; SvmFastRbfBuild times the one-off construction. The model and its protocol: nlos_svm_model.hpp (shared with
// bench/per_sample). Before timing, both predictors are run on every benchmark input and must
// agree (decision value to 1e-9, probabilities to 1e-6), so the comparison is between equal
// computations.
#include <benchmark/benchmark.h>
#include <svm.h>

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_fast_rbf.hpp"
#include "nlos_svm_model.hpp"

namespace {

using namespace ctxfuse::classify;

using Fixture = ctxfuse::bench::NlosSvmBenchModel;

Fixture& fixture() {
  static Fixture f = ctxfuse::bench::build_nlos_svm_bench_model(CTXFUSE_SVM_BENCH_CACHE);
  return f;
}

void SvmPredictProbability_Ours(benchmark::State& state) {
  auto& fx = fixture();
  SvmPrediction<2> out;
  std::size_t i = 0;
  for (auto _ : state) {
    static_cast<void>(svm_predict(fx.ours, fx.inputs[i], out));  // inputs checked by the fixture
    benchmark::DoNotOptimize(out.probabilities[0]);
    i = (i + 1) % fx.inputs.size();
  }
  state.counters["support_vectors"] = static_cast<double>(fx.ours.num_support_vectors());
}

void SvmPredictProbability_LibSvm(benchmark::State& state) {
  auto& fx = fixture();
  double prob[2];
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(svm_predict_probability(fx.libsvm, fx.nodes[i].data(), prob));
    benchmark::DoNotOptimize(prob[0]);
    i = (i + 1) % fx.nodes.size();
  }
  state.counters["support_vectors"] = static_cast<double>(fx.libsvm->l);
}

void SvmDecisionValue_Ours(benchmark::State& state) {
  auto& fx = fixture();
  SvmPrediction<2> out;
  std::size_t i = 0;
  for (auto _ : state) {
    static_cast<void>(svm_decision(fx.ours, fx.inputs[i], out));  // inputs checked by the fixture
    benchmark::DoNotOptimize(out.decision_values[0]);
    i = (i + 1) % fx.inputs.size();
  }
}

void SvmDecisionValue_LibSvm(benchmark::State& state) {
  auto& fx = fixture();
  double dec = 0.0;
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(svm_predict_values(fx.libsvm, fx.nodes[i].data(), &dec));
    benchmark::DoNotOptimize(dec);
    i = (i + 1) % fx.nodes.size();
  }
}

// The fast Gauss transform evaluator (svm_fast_rbf.hpp) on the same model, its automatic choice.
// Before timing it must agree with the exact path on every benchmark input (same label, decision
// value and probabilities to 1e-9) and give libsvm's labels (svm_predict_values and
// svm_predict_probability); the fraction of inputs that fell back to the exact path is reported
// as a counter, with the plan (grid side h, order p, boxes, terms per box).
struct FastFixture {
  SvmFastRbf<2, 2> fast;
  double fallback_predict = 0.0, fallback_decision = 0.0, target = 0.0;
};

SvmFastRbfOptions boxes_only() {
  SvmFastRbfOptions o;
  o.target_grid = false;
  return o;
}

template <bool Target>
FastFixture& fast_fixture() {
  static FastFixture f = [] {
    auto& fx = fixture();
    FastFixture r{SvmFastRbf<2, 2>(fx.ours, Target ? SvmFastRbfOptions{} : boxes_only())};
    long target = 0;
    SvmPrediction<2> exact, out;
    SvmFastReport report;
    long predict_fallbacks = 0, decision_fallbacks = 0;
    for (std::size_t i = 0; i < fx.inputs.size(); ++i) {
      if (!svm_predict(fx.ours, fx.inputs[i], exact) || !r.fast.predict(fx.inputs[i], out, &report))
        throw std::runtime_error("benchmark input " + std::to_string(i) + " refused");
      predict_fallbacks += report.fallback;
      target += report.target;
      double prob[2], dec = 0.0;
      const double libsvm_label = svm_predict_probability(fx.libsvm, fx.nodes[i].data(), prob);
      const double libsvm_vote = svm_predict_values(fx.libsvm, fx.nodes[i].data(), &dec);
      if (out.label != static_cast<int>(libsvm_label))
        throw std::runtime_error("fast prediction and libsvm disagree on benchmark input " + std::to_string(i));
      if (out.label != exact.label || std::abs(out.decision_values[0] - exact.decision_values[0]) > 1e-9 ||
          std::abs(out.probabilities[0] - exact.probabilities[0]) > 1e-9)
        throw std::runtime_error("fast and exact predictions disagree on benchmark input " + std::to_string(i));
      if (!svm_decision(fx.ours, fx.inputs[i], exact) || !r.fast.decision(fx.inputs[i], out, &report))
        throw std::runtime_error("benchmark input " + std::to_string(i) + " refused");
      decision_fallbacks += report.fallback;
      if (out.label != static_cast<int>(libsvm_vote) || std::abs(out.decision_values[0] - dec) > 1e-9)
        throw std::runtime_error("fast decision and libsvm disagree on benchmark input " + std::to_string(i));
      if (out.label != exact.label || std::abs(out.decision_values[0] - exact.decision_values[0]) > 1e-9)
        throw std::runtime_error("fast and exact decisions disagree on benchmark input " + std::to_string(i));
    }
    r.fallback_predict = static_cast<double>(predict_fallbacks) / static_cast<double>(fx.inputs.size());
    r.fallback_decision = static_cast<double>(decision_fallbacks) / static_cast<double>(fx.inputs.size());
    r.target = static_cast<double>(target) / static_cast<double>(fx.inputs.size());
    return r;
  }();
  return f;
}

void plan_counters(benchmark::State& state, const SvmFastRbfPlan& plan) {
  state.counters["fast"] = plan.fast;
  state.counters["h"] = plan.h;
  state.counters["order"] = plan.order;
  state.counters["boxes"] = plan.boxes;
  state.counters["terms"] = plan.terms;
  state.counters["target_h"] = plan.target.h;
  state.counters["target_order"] = plan.target.order;
  state.counters["target_cells"] = static_cast<double>(plan.target.cells);
  state.counters["target_terms"] = plan.target.terms;
}

// SvmPredictProbability/Fast (Probabilities) and SvmDecisionValue/Fast; Target false: /FastBoxes.
template <bool Probabilities, bool Target>
void SvmFast(benchmark::State& state) {
  auto& fx = fixture();
  auto& ff = fast_fixture<Target>();
  SvmPrediction<2> out;
  std::size_t i = 0;
  for (auto _ : state) {
    if constexpr (Probabilities) {
      static_cast<void>(ff.fast.predict(fx.inputs[i], out));  // inputs checked by the fixture
      benchmark::DoNotOptimize(out.probabilities[0]);
    } else {
      static_cast<void>(ff.fast.decision(fx.inputs[i], out));  // inputs checked by the fixture
      benchmark::DoNotOptimize(out.decision_values[0]);
    }
    i = (i + 1) % fx.inputs.size();
  }
  if constexpr (Probabilities) state.counters["support_vectors"] = static_cast<double>(fx.ours.num_support_vectors());
  state.counters["fallback_fraction"] = Probabilities ? ff.fallback_predict : ff.fallback_decision;
  state.counters["target_fraction"] = ff.target;
  plan_counters(state, ff.fast.plan());
}

// The one-off cost of the fast evaluator: choosing (h, p) and building the expansions; Target
// false: the source boxes alone (/FastBoxes).
template <bool Target>
void SvmFastRbfBuild(benchmark::State& state) {
  auto& fx = fixture();
  const SvmFastRbfOptions options = Target ? SvmFastRbfOptions{} : boxes_only();
  for (auto _ : state) {
    SvmFastRbf<2, 2> fast(fx.ours, options);
    benchmark::DoNotOptimize(fast.plan().order);
  }
  plan_counters(state, SvmFastRbf<2, 2>(fx.ours, options).plan());
}

// The kernel block alone (256 support vectors, 2 features) on each compiled instruction set,
// to show what CPUs without AVX-512 get from the exact path.
template <int Variant>
void RbfKernelBlock(benchmark::State& state) {
  using namespace ctxfuse::classify::svm_detail;
#ifdef CTXFUSE_SVM_RUNTIME_AVX2
  if ((Variant == 1 && !cpu_has_avx2_fma()) || (Variant == 2 && !cpu_has_avx512f())) {
    state.SkipWithError("instruction set not available on this CPU");
    return;
  }
#else
  if (Variant != 0) {
    state.SkipWithError("runtime-dispatched variants not compiled on this platform");
    return;
  }
#endif
  auto& fx = fixture();
  const std::array<const double*, 2> columns = {fx.ours.support_vectors.col(0).data(), fx.ours.support_vectors.col(1).data()};
  const double* coef = fx.ours.coefficients.row(0).data();
  alignas(64) std::array<double, kRbfBlock> acc{};
  const RbfExp g = rbf_exp_constants(fx.ours.gamma);
  std::size_t i = 0;
  for (auto _ : state) {
    const std::array<double, 2> x = {fx.inputs[i][0], fx.inputs[i][1]};
    if constexpr (Variant == 0) rbf_block_baseline<2, true>(columns, x, g, acc.data(), coef);
#ifdef CTXFUSE_SVM_RUNTIME_AVX2
    if constexpr (Variant == 1) rbf_block_avx2<2, true>(columns, x, g, acc.data(), coef);
    if constexpr (Variant == 2) rbf_block_avx512<2, true>(columns, x, g, acc.data(), coef);
#endif
    benchmark::DoNotOptimize(acc.data());
    benchmark::ClobberMemory();
    i = (i + 1) % fx.inputs.size();
  }
  state.SetItemsProcessed(state.iterations() * kRbfBlock);
}

// The AVX2-only build (CTXFUSE_SVM_NO_AVX512) names its results apart so that the JSON files of
// both binaries can be read together.
#ifdef CTXFUSE_SVM_NO_AVX512
#define CTXFUSE_BENCH_NAME(base, who) base "Avx2Only/" who
#else
#define CTXFUSE_BENCH_NAME(base, who) base "/" who
BENCHMARK(RbfKernelBlock<0>)->Name("RbfKernelBlock/Baseline");
BENCHMARK(RbfKernelBlock<1>)->Name("RbfKernelBlock/Avx2");
BENCHMARK(RbfKernelBlock<2>)->Name("RbfKernelBlock/Avx512");
#endif

BENCHMARK(SvmPredictProbability_Ours)->Name(CTXFUSE_BENCH_NAME("SvmPredictProbability", "Ours"))->Unit(benchmark::kMicrosecond);
BENCHMARK(SvmPredictProbability_LibSvm)->Name(CTXFUSE_BENCH_NAME("SvmPredictProbability", "LibSvm"))->Unit(benchmark::kMicrosecond);
BENCHMARK(SvmDecisionValue_Ours)->Name(CTXFUSE_BENCH_NAME("SvmDecisionValue", "Ours"))->Unit(benchmark::kMicrosecond);
BENCHMARK(SvmDecisionValue_LibSvm)->Name(CTXFUSE_BENCH_NAME("SvmDecisionValue", "LibSvm"))->Unit(benchmark::kMicrosecond);
BENCHMARK(SvmFast<true, true>)->Name(CTXFUSE_BENCH_NAME("SvmPredictProbability", "Fast"))->Unit(benchmark::kMicrosecond);
BENCHMARK(SvmFast<false, true>)->Name(CTXFUSE_BENCH_NAME("SvmDecisionValue", "Fast"))->Unit(benchmark::kMicrosecond);
BENCHMARK(SvmFast<true, false>)->Name(CTXFUSE_BENCH_NAME("SvmPredictProbability", "FastBoxes"))->Unit(benchmark::kMicrosecond);
BENCHMARK(SvmFast<false, false>)->Name(CTXFUSE_BENCH_NAME("SvmDecisionValue", "FastBoxes"))->Unit(benchmark::kMicrosecond);
BENCHMARK(SvmFastRbfBuild<true>)->Name(CTXFUSE_BENCH_NAME("SvmFastRbfBuild", "Fast"))->Unit(benchmark::kMillisecond);
BENCHMARK(SvmFastRbfBuild<false>)->Name(CTXFUSE_BENCH_NAME("SvmFastRbfBuild", "FastBoxes"))->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

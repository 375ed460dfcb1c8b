// SvmPredictProbability/Ours vs /LibSvm: the same libsvm model file, loaded by libsvm and by our
// loader, the same inputs. The model follows the NLOS paper's protocol (digest section C): UWB
// ranges to 4 anchors along a simulated drive, half of each anchor's sequence made NLOS by
// adding positive noise with mean 1-2 m, features (v_u range rate, v_i vehicle speed), RBF
// C-SVC with probabilities. The heavy LOS/NLOS overlap of range rates leaves >10,000 SVs.
//
// Before timing, both predictors are run on every benchmark input and must agree (decision
// value to 1e-9, probabilities to 1e-6), so the comparison is between equal computations.
#include <benchmark/benchmark.h>
#include <svm.h>

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "ctxfuse/classify/svm.hpp"
#include "ctxfuse/classify/svm_io.hpp"

namespace {

using namespace ctxfuse::classify;

struct Sample {
  double range_rate;  // v_u [m/s]
  double speed;       // v_i [m/s]
  int nlos;
};

/// A drive around a 120 m x 70 m loop at 1-9 m/s, UWB at 10 Hz to 4 anchors with 0.1 m
/// ranging noise. Each anchor's sequence alternates LOS and NLOS blocks of 2-10 s (half NLOS);
/// in an NLOS block every range gets a positive error mu * g, g ~ Gamma(40, 1/40) (mean 1),
/// with mu ~ U(1, 2) m drawn per block.
std::vector<Sample> simulate_drive(int samples_per_anchor, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::gamma_distribution<double> excess(40.0, 1.0 / 40.0);
  const double dt = 0.1;
  const std::array<Eigen::Vector2d, 4> anchors = {Eigen::Vector2d(-10, -8), Eigen::Vector2d(130, -6),
                                                  Eigen::Vector2d(128, 78), Eigen::Vector2d(-8, 80)};
  const double perimeter = 2 * (120.0 + 70.0);
  const auto position = [&](double s) {
    s = std::fmod(s, perimeter);
    if (s < 120) return Eigen::Vector2d(s, 0);
    if (s < 190) return Eigen::Vector2d(120, s - 120);
    if (s < 310) return Eigen::Vector2d(310 - s, 70);
    return Eigen::Vector2d(0, perimeter - s);
  };
  std::vector<Sample> out;
  for (std::size_t a = 0; a < anchors.size(); ++a) {
    double travelled = 0.0, previous_range = 0.0;
    int block_left = 0;
    bool nlos = false;
    double mu = 0.0;
    for (int k = 0; k <= samples_per_anchor; ++k) {
      const double t = k * dt;
      const double speed = 5.0 + 4.0 * std::sin(0.031 * t + static_cast<double>(a)) * std::cos(0.007 * t);
      travelled += speed * dt;
      if (block_left-- <= 0) {
        block_left = 20 + static_cast<int>(u01(rng) * 80);
        nlos = u01(rng) < 0.5;
        mu = 1.0 + u01(rng);
      }
      double range = (position(travelled) - anchors[a]).norm() + 0.1 * n01(rng);
      if (nlos) range += mu * excess(rng);
      if (k > 0) out.push_back({(range - previous_range) / dt, speed + 0.05 * n01(rng), nlos ? 1 : 0});
      previous_range = range;
    }
  }
  return out;
}

struct Fixture {
  svm_model* libsvm = nullptr;
  SvmModel<2, 2> ours;
  std::vector<Eigen::Vector2d> inputs;
  std::vector<std::array<svm_node, 3>> nodes;
};

void quiet(const char*) {}

Fixture& fixture() {
  static Fixture f = [] {
    Fixture fx;
    svm_set_print_string_function(&quiet);
    // Standardise with the training set's mean/std (the model file then needs no scaling).
    // CTXFUSE_BENCH_SMOKE (set by scripts/bench_smoke.sh in CI) only shows that the binary
    // runs: a small model, its own cache file, no minutes of libsvm training.
    const bool smoke = std::getenv("CTXFUSE_BENCH_SMOKE") != nullptr;
    const auto train = simulate_drive(smoke ? 250 : 6250, 1);
    Eigen::Vector2d mean = Eigen::Vector2d::Zero(), sq = Eigen::Vector2d::Zero();
    for (const auto& s : train) mean += Eigen::Vector2d(s.range_rate, s.speed);
    mean /= static_cast<double>(train.size());
    for (const auto& s : train) sq += (Eigen::Vector2d(s.range_rate, s.speed) - mean).cwiseAbs2();
    const Eigen::Vector2d stdev = (sq / static_cast<double>(train.size())).cwiseSqrt();
    const auto standardise = [&](const Sample& s) { return Eigen::Vector2d((s.range_rate - mean[0]) / stdev[0], (s.speed - mean[1]) / stdev[1]); };
    const std::string cache = std::string(CTXFUSE_SVM_BENCH_CACHE) + (smoke ? ".smoke" : "");
    if (!std::filesystem::exists(cache)) {
      std::fprintf(stderr, "training the benchmark model with libsvm on %zu samples (cached in %s) ...\n", train.size(), cache.c_str());
      std::vector<std::array<svm_node, 3>> rows(train.size());
      std::vector<svm_node*> ptrs(train.size());
      std::vector<double> y(train.size());
      for (std::size_t i = 0; i < train.size(); ++i) {
        const auto x = standardise(train[i]);
        rows[i] = {svm_node{1, x[0]}, svm_node{2, x[1]}, svm_node{-1, 0.0}};
        ptrs[i] = rows[i].data();
        y[i] = train[i].nlos;
      }
      svm_problem prob{static_cast<int>(train.size()), y.data(), ptrs.data()};
      svm_parameter p{};
      p.svm_type = C_SVC;
      p.kernel_type = RBF;
      p.gamma = 0.5;
      p.C = 1.0;
      p.cache_size = 500;
      p.eps = 1e-3;
      p.shrinking = 1;
      p.probability = 1;
      std::srand(1);
      svm_model* trained = svm_train(&prob, &p);
      const auto tmp = cache + ".tmp";
      if (svm_save_model(tmp.c_str(), trained) != 0) throw std::runtime_error("cannot write " + tmp);
      std::filesystem::rename(tmp, cache);
      svm_free_and_destroy_model(&trained);
    }
    fx.libsvm = svm_load_model(cache.c_str());
    if (!fx.libsvm) throw std::runtime_error("libsvm cannot load " + cache);
    fx.ours = load_svm_model<2, 2>(cache);
    for (const auto& s : simulate_drive(256, 2)) {
      fx.inputs.push_back(standardise(s));
      fx.nodes.push_back({svm_node{1, fx.inputs.back()[0]}, svm_node{2, fx.inputs.back()[1]}, svm_node{-1, 0.0}});
    }
    SvmPrediction<2> out;
    for (std::size_t i = 0; i < fx.inputs.size(); ++i) {
      double dec = 0.0, prob[2];
      svm_predict_values(fx.libsvm, fx.nodes[i].data(), &dec);
      svm_predict_probability(fx.libsvm, fx.nodes[i].data(), prob);
      svm_predict(fx.ours, fx.inputs[i], out);
      if (std::abs(out.decision_values[0] - dec) > 1e-9 * std::max(1.0, std::abs(dec)) || std::abs(out.probabilities[0] - prob[0]) > 1e-6)
        throw std::runtime_error("ours and libsvm disagree on benchmark input " + std::to_string(i));
    }
    return fx;
  }();
  return f;
}

void SvmPredictProbability_Ours(benchmark::State& state) {
  auto& fx = fixture();
  SvmPrediction<2> out;
  std::size_t i = 0;
  for (auto _ : state) {
    svm_predict(fx.ours, fx.inputs[i], out);
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
    svm_decision(fx.ours, fx.inputs[i], out);
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
  std::size_t i = 0;
  for (auto _ : state) {
    const std::array<double, 2> x = {fx.inputs[i][0], fx.inputs[i][1]};
    const double g = -fx.ours.gamma;
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

}  // namespace

BENCHMARK_MAIN();

// One IMM step with three 15-state error-state modes (Ins15Model; GNSS position + one UWB
// range each), against three independent ESKF steps doing the same predictions and updates:
// the ratio is what mixing, scoring, the probability update and the combination cost.
// Run: bench_imm --benchmark_out=imm.json --benchmark_out_format=json
#include <benchmark/benchmark.h>

#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/filters/imm.hpp"
#include "ctxfuse/models/ins.hpp"
#include "ctxfuse/models/ins_range.hpp"
#include "ctxfuse/policies/mixing.hpp"

namespace {
using namespace ctxfuse;
namespace hana = boost::hana;
using M = models::Ins15Model;

struct GnssTag {};
struct UwbTag {};

struct Setup {
  models::ImuSample u;
  models::GnssPosition<> gnss;
  models::InsRange<> range;
  eskf::Belief<M> init;
  Setup() {
    u.accel << 0.1, 0.02, 9.81;
    u.gyro << 0.001, -0.002, 0.05;
    gnss.R = SquareMatrix<3>::Identity() * 4.0;
    range.anchor << 5.0, 5.0, 2.0;
    range.sigma = 0.15;
    init.cov = SquareMatrix<15>::Identity() * 0.01;
  }
};

M mode_model(double accel_density) {
  M m;
  m.accel_noise_density = accel_density;
  return m;
}

void BM_ImmStep3Eskf15(benchmark::State& state) {
  Setup s;
  auto modes = hana::make_tuple(imm::make_mode(mode_model(0.01), imm::AcceptsAll{}, ChiSquareGate(0.9999)),
                                imm::make_mode(mode_model(0.02), imm::AcceptsAll{}, ChiSquareGate(0.9999)),
                                imm::make_mode(mode_model(0.05), imm::AcceptsAll{}, ChiSquareGate(0.9999)));
  imm::Imm f(policies::FixedTransition<3>(policies::sticky_transition<3>(0.95)), modes, s.init,
             Vector<3>::Constant(1.0 / 3.0));
  double t = 0.0;
  for (auto _ : state) {
    f.mix();
    benchmark::DoNotOptimize(f.predict(s.u, 0.01));
    t += 0.01;
    benchmark::DoNotOptimize(f.update(GnssTag{}, s.gnss, Vector<3>(0.05 * t, 0.0, 0.0)));
    benchmark::DoNotOptimize(f.update(UwbTag{}, s.range, Vector<1>(7.0)));
    f.update_mode_probabilities();
    auto c = f.combined();
    benchmark::DoNotOptimize(c);
  }
}
BENCHMARK(BM_ImmStep3Eskf15);

void BM_ThreeIndependentEskf15(benchmark::State& state) {
  Setup s;
  Eskf<M, ChiSquareGate> a(mode_model(0.01), s.init, {}, ChiSquareGate(0.9999));
  Eskf<M, ChiSquareGate> b(mode_model(0.02), s.init, {}, ChiSquareGate(0.9999));
  Eskf<M, ChiSquareGate> c(mode_model(0.05), s.init, {}, ChiSquareGate(0.9999));
  double t = 0.0;
  for (auto _ : state) {
    t += 0.01;
    const Vector<3> z(0.05 * t, 0.0, 0.0);
    for (auto* f : {&a, &b, &c}) {
      benchmark::DoNotOptimize(f->predict(s.u, 0.01));
      benchmark::DoNotOptimize(f->update(s.gnss, z));
      benchmark::DoNotOptimize(f->update(s.range, Vector<1>(7.0)));
    }
  }
}
BENCHMARK(BM_ThreeIndependentEskf15);

}  // namespace

BENCHMARK_MAIN();

// The two workloads of bench_imm, shared by the Google Benchmark binary and by the plain step
// driver used for callgrind instruction counts (bench_imm_steps).
#pragma once

#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/filters/imm.hpp"
#include "ctxfuse/models/ins.hpp"
#include "ctxfuse/models/ins_range.hpp"
#include "ctxfuse/policies/mixing.hpp"

namespace imm_bench {
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

inline M mode_model(double accel_density) {
  M m;
  m.accel_noise_density = accel_density;
  return m;
}

inline auto make_imm(const Setup& s) {
  auto modes = hana::make_tuple(imm::make_mode(mode_model(0.01), imm::AcceptsAll{}, policies::ChiSquareGate(0.9999)),
                                imm::make_mode(mode_model(0.02), imm::AcceptsAll{}, policies::ChiSquareGate(0.9999)),
                                imm::make_mode(mode_model(0.05), imm::AcceptsAll{}, policies::ChiSquareGate(0.9999)));
  return imm::Imm(policies::FixedTransition<3>(policies::sticky_transition<3>(0.95)), modes, s.init,
                  Vector<3>::Constant(1.0 / 3.0));
}

/// One IMM step: mix, predict, GNSS, UWB, mode probabilities, combined estimate. `keep`
/// stops the compiler from discarding a result.
template <class Imm, class Keep>
void imm_step(Imm& f, const Setup& s, double& t, Keep&& keep) {
  keep(f.mix());
  keep(f.predict(s.u, 0.01));
  t += 0.01;
  keep(f.update(GnssTag{}, s.gnss, Vector<3>(0.05 * t, 0.0, 0.0)));
  keep(f.update(UwbTag{}, s.range, Vector<1>(7.0)));
  f.update_mode_probabilities();
  auto c = f.combined();
  keep(c);
}

struct ThreeEskf {
  Eskf<M, policies::ChiSquareGate> a, b, c;
  explicit ThreeEskf(const Setup& s)
      : a(mode_model(0.01), s.init, {}, policies::ChiSquareGate(0.9999)),
        b(mode_model(0.02), s.init, {}, policies::ChiSquareGate(0.9999)),
        c(mode_model(0.05), s.init, {}, policies::ChiSquareGate(0.9999)) {}
};

/// The same predictions and updates by three independent ESKFs.
template <class Keep>
void three_eskf_step(ThreeEskf& e, const Setup& s, double& t, Keep&& keep) {
  t += 0.01;
  const Vector<3> z(0.05 * t, 0.0, 0.0);
  for (auto* f : {&e.a, &e.b, &e.c}) {
    keep(f->predict(s.u, 0.01));
    keep(f->update(s.gnss, z));
    keep(f->update(s.range, Vector<1>(7.0)));
  }
}

}  // namespace imm_bench

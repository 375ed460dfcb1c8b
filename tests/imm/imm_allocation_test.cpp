// The IMM step (mix, predict, routed updates, probability update, combination) must not touch
// the heap, for vector modes (planar sub-models) and for error-state modes (15-state INS),
// whether run step by step or as one Imm::cycle().
// Counting operator new plus Eigen's runtime malloc guard, as tests/filters/allocation_test.cpp.
#include "support/heap_counter.hpp"

#include <gtest/gtest.h>

#include "ctxfuse/filters/imm.hpp"
#include "ctxfuse/models/ins.hpp"
#include "ctxfuse/models/ins_range.hpp"
#include "ctxfuse/models/planar.hpp"
#include "ctxfuse/policies/mixing.hpp"

namespace {
using namespace ctxfuse;
namespace hana = boost::hana;

using test::heap_uses;

struct GnssTag {};
struct UwbTag {};

// The region pipeline's shape: three planar modes routed by GNSS/UWB tags, and their inputs.
struct Planar {
  using M = models::PlanarImuModel;
  static auto modes() {
    return hana::make_tuple(imm::make_mode(M{}, imm::Accepts<GnssTag>{}, policies::ChiSquareGate(0.999)),
                            imm::make_mode(M{}, imm::Accepts<GnssTag, UwbTag>{}, policies::ChiSquareGate(0.999)),
                            imm::make_mode(M{}, imm::Accepts<UwbTag>{}, policies::ChiSquareGate(0.999)));
  }
  Gaussian<8> init;
  models::PlanarImu u;
  models::PlanarPosition gnss;
  models::PlanarRange range;
  Planar() {
    init.cov *= 0.1;
    u.yaw_rate = 0.05;
    u.accel << 0.2, 0.0;
    range.anchor << 10.0, 5.0, 3.0;
  }
};

TEST(ImmAllocation, PlanarRegionImmStepNeverAllocates) {
  const Planar p;
  const auto& u = p.u;  // references, not a structured binding: clang 14 cannot capture those
  const auto& gnss = p.gnss;
  const auto& range = p.range;
  imm::Imm f(policies::RegionAdaptiveTransition<3, 16>(policies::sticky_transition<3>(0.9), 0.5, 0.5), Planar::modes(),
             p.init, Vector<3>::Constant(1.0 / 3.0));
  int scored = 0, mixed = 0;
  EXPECT_EQ(heap_uses([&] {
              for (int k = 0; k < 300; ++k) {
                f.mixing().observe_region(k / 100);
                mixed += f.mix().accepted();
                for (int i = 0; i < 10; ++i) (void)f.predict(u, 0.01);
                scored += f.update(UwbTag{}, hana::make_tuple(range, range, range), Vector<1>(11.0), 0b110u).scored;
                scored += f.update(GnssTag{}, gnss, Vector<2>(0.01 * k, 0.0)).scored;
                (void)f.update(GnssTag{}, gnss, Vector<2>(1e5, 0.0));  // gated everywhere
                f.update_mode_probabilities();
                (void)f.combined();
              }
            }),
            0);
  EXPECT_GT(scored, 300);
  EXPECT_EQ(mixed, 300);
}

TEST(ImmAllocation, ErrorStateInsImmStepNeverAllocates) {
  using M = models::Ins15Model;
  auto modes = hana::make_tuple(imm::make_mode(M{}), imm::make_mode(M{}), imm::make_mode(M{}));
  eskf::Belief<M> init;
  init.cov = SquareMatrix<15>::Identity() * 0.01;
  imm::Imm f(policies::FixedTransition<3>(policies::sticky_transition<3>(0.9)), modes, init, Vector<3>::Constant(1.0 / 3.0));
  models::ImuSample u;
  u.accel << 0.1, 0.0, 9.81;
  u.gyro << 0.0, 0.0, 0.05;
  models::GnssPosition<> gnss;
  models::InsRange<> range;
  range.anchor << 5.0, 5.0, 2.0;
  int mixed = 0;
  EXPECT_EQ(heap_uses([&] {
              for (int k = 0; k < 200; ++k) {
                mixed += f.mix().accepted();
                (void)f.predict(u, 0.01);
                (void)f.update(GnssTag{}, gnss, Vector<3>(0.001 * k, 0.0, 0.0));
                (void)f.update(UwbTag{}, range, Vector<1>(7.1));
                f.update_mode_probabilities();
                (void)f.combined();
              }
            }),
            0);
  EXPECT_EQ(mixed, 200);
  EXPECT_NEAR(f.mode_probabilities().sum(), 1.0, 1e-12);
  EXPECT_TRUE(f.combined().nominal.p.allFinite());
}

TEST(ImmAllocation, OneCallCycleNeverAllocates) {
  const Planar p;
  const auto& u = p.u;  // references, not a structured binding: clang 14 cannot capture those
  const auto& gnss = p.gnss;
  const auto& range = p.range;
  imm::ImmOptions<3> o;
  o.prior_weights = imm::PriorWeights::predicted;
  imm::Imm f(policies::FixedTransition<3>(policies::sticky_transition<3>(0.9)), Planar::modes(), p.init,
             Vector<3>::Constant(1.0 / 3.0), o);
  int closed = 0;
  EXPECT_EQ(heap_uses([&] {
              for (int k = 0; k < 300; ++k) {
                const auto r = f.cycle(u, 0.1, imm::observe(UwbTag{}, hana::make_tuple(range, range, range), Vector<1>(11.0), 0b110u),
                                       imm::observe(GnssTag{}, gnss, Vector<2>(0.01 * k, 0.0)));
                closed += r.status().accepted() && !f.cycle_open();
                (void)f.combined();
              }
            }),
            0);
  EXPECT_EQ(closed, 300);
}

}  // namespace

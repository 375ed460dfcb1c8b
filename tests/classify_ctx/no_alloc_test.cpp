// The per-sample steps must not allocate: count global operator new calls around them.
#include <gtest/gtest.h>

#include <ctxfuse/classify/consistency.hpp>
#include <ctxfuse/classify/dempster_shafer.hpp>
#include <ctxfuse/classify/hmm.hpp>
#include <ctxfuse/classify/joint.hpp>
#include <ctxfuse/classify/region_transition.hpp>
#include <ctxfuse/features/gnss_scene.hpp>
#include <ctxfuse/features/nlos.hpp>

#include <atomic>
#include <cstdlib>
#include <new>
#include <vector>

namespace {
std::atomic<long> g_allocations{0};
}

void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace {

using namespace ctxfuse;

TEST(NoAllocation, PerSampleSteps) {
  Eigen::Vector3d pi(0.5, 0.3, 0.2);
  Eigen::Matrix3d a;
  a << 0.9, 0.08, 0.02, 0.05, 0.9, 0.05, 0.02, 0.08, 0.9;
  std::array<Eigen::Vector2d, 3> mu{Eigen::Vector2d(20, 40), Eigen::Vector2d(12, 33), Eigen::Vector2d(4, 25)};
  std::array<Eigen::Matrix2d, 3> cov;
  for (auto& c : cov) c << 4, 1, 1, 3;
  const auto hmm = classify::make_gaussian_hmm<3, 2>(pi, a, mu, cov);
  classify::HmmForwardFilter<3, 2> filter(hmm);
  const auto vote = classify::WeightedVote<3, 2>::from_accuracies({{{0.9, 0.8, 0.95}, {0.85, 0.9, 0.8}}});
  classify::RegionTransitionCounter<3> counter;
  const classify::ConsistencyModel consistency;
  features::GnssSceneExtractor<> scene;
  const std::vector<features::SatelliteObservation> sats{
      {1, 20, 10, 40}, {2, 40, 100, 44}, {3, 60, 300, 48}, {4, 35, 200, 38}, {5, 15, 250, 30}};
  features::NlosFeatureExtractor nlos;
  features::RangeWindowFeatures<64> window(10);

  // The counter itself must see allocations, or the final check would prove nothing.
  const long probe = g_allocations.load();
  int* volatile probe_ptr = new int(1);
  delete probe_ptr;
  ASSERT_EQ(g_allocations.load() - probe, 1);

  const long before = g_allocations.load();
  double sink = 0.0;
  for (int t = 0; t < 200; ++t) {
    ASSERT_TRUE(filter.step(Eigen::Vector2d(4.0 + t % 17, 25.0 + t % 13)).accepted());
    const int region = filter.most_probable();
    counter.add(vote({region, (region + t) % 3}));
    sink += counter.matrix()(0, 0);
    const double p2 = consistency.nlos_probability(0.01 * (t % 50), 0.1);
    sink += classify::combine_probabilities(0.7, p2).nlos_belief();
    const std::array<classify::BinaryMass, 3> three{classify::BinaryMass::from_probability(0.6),
                                                    classify::BinaryMass::from_probability(p2),
                                                    classify::BinaryMass{0.2, 0.3, 0.5}};
    sink += classify::combine(std::span<const classify::BinaryMass>(three)).conflict;
    features::GnssSceneFeatures f;
    ASSERT_TRUE(scene.push({double(t), sats}, f).accepted());
    sink += f[0];
    features::NlosFeatures nf;
    ASSERT_TRUE(nlos.push({0.1 * t, 10.0 + 0.01 * t, -80, -81}, 1.0, nf).accepted());
    features::RangeWindowFeatures<64>::Output wo;
    ASSERT_TRUE(window.push(0.01 * t, -80, -81, wo).accepted());
    sink += wo.residual_mean_m;
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace

// The region pipeline's wiring, checked by reductions to independent references on a
// simulated drive: the region-aware IMM with w_m = 0 and every label "transition" (which
// routes every measurement to every sub-model that takes it) is the plain IMM, exactly; the
// single-sub-model runs are the EKFs the IMM is built from.
#include <gtest/gtest.h>

#include "ctxfuse/pipelines/region_imm.hpp"

namespace {
using namespace ctxfuse;
namespace ri = pipelines::region_imm;

const sim::Drive& drive() {
  static const sim::Drive d = [] {
    sim::DriveConfig c;
    c.seed = 11;
    return sim::simulate_drive(c);
  }();
  return d;
}

TEST(RegionPipeline, RegionImmWithoutRegionInformationIsThePlainImm) {
  ri::Settings s;
  s.prior_weight = 1.0;
  const std::vector<int> all_transition(drive().gnss.size(), 1);
  const auto plain = ri::run(drive(), ri::Estimator::imm, s);
  const auto region = ri::run(drive(), ri::Estimator::region_imm, s, &all_transition);
  ASSERT_EQ(plain.t.size(), region.t.size());
  ASSERT_GT(plain.t.size(), 100u);
  for (std::size_t i = 0; i < plain.t.size(); ++i) {
    EXPECT_EQ(plain.estimate[i], region.estimate[i]) << "epoch " << i;
    EXPECT_EQ(plain.dominant_mode[i], region.dominant_mode[i]);
  }
}

TEST(RegionPipeline, RoutingChangesTheEstimateOnlyWhereItExcludesASensor) {
  // Labels "outdoor" everywhere: UWB is kept from every sub-model. Before the first UWB range
  // arrives the two runs must agree exactly; afterwards they must differ.
  ri::Settings s;
  s.prior_weight = 1.0;
  const std::vector<int> all_transition(drive().gnss.size(), 1), all_outdoor(drive().gnss.size(), 0);
  const auto a = ri::run(drive(), ri::Estimator::region_imm, s, &all_transition);
  const auto b = ri::run(drive(), ri::Estimator::region_imm, s, &all_outdoor);
  ASSERT_FALSE(drive().uwb.empty());
  const double first_uwb = drive().uwb.front().t;
  bool differs_later = false;
  for (std::size_t i = 0; i < a.t.size(); ++i) {
    if (a.t[i] < first_uwb - 1e-9) {
      EXPECT_EQ(a.estimate[i], b.estimate[i]) << "t " << a.t[i];
    } else {
      differs_later |= a.estimate[i] != b.estimate[i];
    }
  }
  EXPECT_TRUE(differs_later);
}

TEST(RegionPipeline, ErrorsAreMeansOverTheRegionsSamples) {
  ri::Track tr;
  tr.t = {0, 1, 2};
  tr.estimate = {Eigen::Vector2d(3, 4), Eigen::Vector2d(0, 1), Eigen::Vector2d(1, 0)};
  tr.truth = {Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 0)};
  tr.region = {0, 2, 2};
  const auto e = ri::errors(tr);
  EXPECT_DOUBLE_EQ(e.mean[0], 5.0);
  EXPECT_DOUBLE_EQ(e.mean[2], 1.0);
  EXPECT_DOUBLE_EQ(e.mean[3], 7.0 / 3.0);
  EXPECT_DOUBLE_EQ(e.rmse_x[3], std::sqrt((9.0 + 0.0 + 1.0) / 3.0));
  EXPECT_EQ(e.count[1], 0u);
}

}  // namespace

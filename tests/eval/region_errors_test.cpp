// Scoring of planar tracks per true region (eval/region_errors.hpp) and truth lookups
// (eval/truth.hpp), against hand computations.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "ctxfuse/eval/region_errors.hpp"

namespace {
using namespace ctxfuse;

sim::TruthSample sample(double t, double x, double y, sim::Region r) {
  sim::TruthSample s;
  s.t = t;
  s.position = Eigen::Vector3d(x, y, 0.0);
  s.region = r;
  return s;
}

TEST(RegionErrors, ScoresSolutionsApartFromHeldPositions) {
  // Four epochs, errors 1, 3 (outdoor) and 2, 4 (indoor) along x; only the first has a solution.
  const std::array<double, 4> err{1.0, 3.0, 2.0, 4.0};
  eval::TrackTruth truth;
  std::vector<Eigen::Vector2d> estimate;
  std::vector<bool> solution;
  for (std::size_t i = 0; i < 4; ++i) {
    truth.position.emplace_back(10.0, -5.0);
    truth.region.push_back(i < 2 ? 0 : 2);
    estimate.emplace_back(10.0 + err[i], -5.0);
    solution.push_back(i == 0);
  }
  const auto e = eval::region_errors(estimate, solution, truth);
  EXPECT_DOUBLE_EQ(e.mean[0], 2.0);
  EXPECT_DOUBLE_EQ(e.mean[2], 3.0);
  EXPECT_DOUBLE_EQ(e.mean[3], 2.5);
  EXPECT_DOUBLE_EQ(e.mean_with_solution[0], 1.0);
  EXPECT_DOUBLE_EQ(e.mean_with_solution[3], 1.0);
  EXPECT_TRUE(std::isnan(e.mean_with_solution[2]));
  EXPECT_TRUE(std::isnan(e.mean_with_solution[1]));  // no transition epoch at all
  EXPECT_DOUBLE_EQ(e.availability(0), 0.5);
  EXPECT_DOUBLE_EQ(e.availability(2), 0.0);
  EXPECT_DOUBLE_EQ(e.availability(3), 0.25);
  EXPECT_DOUBLE_EQ(e.availability(1), 0.0);
}

TEST(RegionErrors, MeansAndRmseOverTheRegionsEpochs) {
  eval::TrackTruth truth{{Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 0)}, {0, 2, 2}};
  const std::vector<Eigen::Vector2d> estimate{Eigen::Vector2d(3, 4), Eigen::Vector2d(0, 1), Eigen::Vector2d(1, 0)};
  const auto e = eval::region_errors(estimate, {}, truth);
  EXPECT_DOUBLE_EQ(e.mean[0], 5.0);
  EXPECT_DOUBLE_EQ(e.mean[2], 1.0);
  EXPECT_DOUBLE_EQ(e.mean[3], 7.0 / 3.0);
  EXPECT_DOUBLE_EQ(e.rmse_x[3], std::sqrt((9.0 + 0.0 + 1.0) / 3.0));
  EXPECT_DOUBLE_EQ(e.rmse_y[3], std::sqrt((16.0 + 1.0 + 0.0) / 3.0));
  EXPECT_EQ(e.count[1], 0u);
  EXPECT_EQ(e.with_solution[3], 3u);  // no solution flags: every epoch has one
}

TEST(TruthLookup, PositionIsInterpolatedAndTheRegionIsTheSampleAtOrBefore) {
  const std::vector<sim::TruthSample> truth{sample(0.0, 0, 0, sim::Region::outdoor), sample(1.0, 10, 2, sim::Region::transition),
                                            sample(2.0, 20, 2, sim::Region::indoor)};
  EXPECT_EQ(eval::position_at(truth, 1.0), Eigen::Vector3d(10, 2, 0));  // exactly a sample
  EXPECT_LT((eval::position_at(truth, 0.25) - Eigen::Vector3d(2.5, 0.5, 0)).norm(), 1e-12);
  EXPECT_EQ(eval::position_at(truth, -1.0), Eigen::Vector3d(0, 0, 0));  // held at the ends
  EXPECT_EQ(eval::position_at(truth, 5.0), Eigen::Vector3d(20, 2, 0));
  EXPECT_EQ(eval::region_at(truth, 0.999), 0);
  EXPECT_EQ(eval::region_at(truth, 1.0), 1);
  EXPECT_EQ(eval::region_at(truth, 7.0), 2);
  const std::vector<double> times{0.5, 1.5, 2.0};
  EXPECT_EQ(eval::region_labels(truth, times), (std::vector<int>{0, 1, 2}));
  EXPECT_THROW((void)eval::position_at(std::vector<sim::TruthSample>{}, 0.0), std::invalid_argument);
}

}  // namespace

// Metrics against values computed by hand (worked out in the comments).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "ctxfuse/classify/confusion_matrix.hpp"
#include "ctxfuse/eval/position_error.hpp"

namespace ev = ctxfuse::eval;

TEST(EvalPercentile, Type7LinearInterpolation) {
  // Sorted {1,2,3,4}: h = 3p/100. p=50: h=1.5 -> 2.5; p=90: h=2.7 -> 3 + 0.7 = 3.7.
  EXPECT_DOUBLE_EQ(ev::percentile({4, 1, 3, 2}, 50), 2.5);
  EXPECT_DOUBLE_EQ(ev::percentile({4, 1, 3, 2}, 90), 3.7);
  EXPECT_DOUBLE_EQ(ev::percentile({4, 1, 3, 2}, 0), 1.0);
  EXPECT_DOUBLE_EQ(ev::percentile({4, 1, 3, 2}, 100), 4.0);
  EXPECT_DOUBLE_EQ(ev::percentile({5}, 67), 5.0);
  EXPECT_TRUE(std::isnan(ev::percentile({}, 50)));
  EXPECT_THROW((void)ev::percentile({1, 2}, 101), std::invalid_argument);
}

TEST(EvalPositionError, HandComputedStatistics) {
  // Horizontal errors {5, 0, 10, 1}: mean 4; rmse sqrt((25+0+100+1)/4) = sqrt(31.5);
  // std sqrt((1+16+36+9)/4) = sqrt(15.5); sorted {0,1,5,10}: p50 h=1.5 -> 3, p67 h=2.01 -> 5.05,
  // p70 h=2.1 -> 5.5, p75 h=2.25 -> 6.25, p90 h=2.7 -> 8.5, p95 h=2.85 -> 9.25.
  const std::vector<Eigen::Vector3d> e{{3, 4, 0}, {0, 0, 0}, {6, 8, 0}, {1, 0, 2}};
  const auto s = ev::position_error_stats(e);
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.horizontal.mean, 4.0);
  EXPECT_DOUBLE_EQ(s.horizontal.rmse, std::sqrt(31.5));
  EXPECT_DOUBLE_EQ(s.horizontal.max, 10.0);
  EXPECT_DOUBLE_EQ(s.horizontal.std, std::sqrt(15.5));
  const double expected[] = {3.0, 5.05, 5.5, 6.25, 8.5, 9.25};
  for (std::size_t i = 0; i < 6; ++i) EXPECT_NEAR(s.horizontal.percentiles[i], expected[i], 1e-12) << ev::kPercentileLevels[i];
  EXPECT_NEAR(s.horizontal.at(67), 5.05, 1e-12);
  EXPECT_THROW((void)s.horizontal.at(80), std::invalid_argument);
  // Axes: east {3,0,6,1} mean 2.5, rmse sqrt(46/4); north {4,0,8,0} mean 3, rmse sqrt(80/4);
  // up {0,0,0,2} rmse 1.
  EXPECT_DOUBLE_EQ(s.mean_axis.x(), 2.5);
  EXPECT_DOUBLE_EQ(s.mean_axis.y(), 3.0);
  EXPECT_DOUBLE_EQ(s.rmse_axis.x(), std::sqrt(11.5));
  EXPECT_DOUBLE_EQ(s.rmse_axis.y(), std::sqrt(20.0));
  EXPECT_DOUBLE_EQ(s.rmse_axis.z(), 1.0);
  // |east| sorted {0,1,3,6}: p50 = 2; 3-D norms {5,0,10,sqrt(5)}: max 10.
  EXPECT_DOUBLE_EQ(s.east_abs.at(50), 2.0);
  EXPECT_DOUBLE_EQ(s.spatial.max, 10.0);
  // rmse^2 = mean^2 + std^2 holds with the population std.
  EXPECT_NEAR(s.horizontal.rmse * s.horizontal.rmse, s.horizontal.mean * s.horizontal.mean + s.horizontal.std * s.horizontal.std, 1e-12);
}

TEST(EvalPositionError, PerLabelBreakdownAndBadInput) {
  const std::vector<Eigen::Vector3d> e{{3, 4, 0}, {0, 0, 0}, {6, 8, 0}, {1, 0, 2}};
  const std::vector<int> labels{0, 1, 0, 2};
  const auto by = ev::position_error_stats_by_label(e, labels, 4);
  ASSERT_EQ(by.size(), 4u);
  EXPECT_EQ(by[0].count, 2u);
  EXPECT_DOUBLE_EQ(by[0].horizontal.mean, 7.5);  // (5 + 10) / 2
  EXPECT_DOUBLE_EQ(by[0].horizontal.std, 2.5);
  EXPECT_DOUBLE_EQ(by[1].horizontal.max, 0.0);
  EXPECT_DOUBLE_EQ(by[2].horizontal.mean, 1.0);
  EXPECT_EQ(by[3].count, 0u);
  EXPECT_TRUE(std::isnan(by[3].horizontal.mean));
  EXPECT_THROW((void)ev::position_error_stats_by_label(e, std::vector<int>{0, 1, 5, 0}, 3), std::invalid_argument);
  EXPECT_THROW((void)ev::position_error_stats_by_label(e, std::vector<int>{0, 1}, 3), std::invalid_argument);
  const std::vector<Eigen::Vector3d> bad{{1, 0, 0}, {NAN, 0, 0}};
  try {
    (void)ev::position_error_stats(bad);
    FAIL();
  } catch (const std::invalid_argument& x) {
    EXPECT_NE(std::string(x.what()).find("sample 1"), std::string::npos) << x.what();
  }
}

TEST(EvalConfusion, HandComputedScores) {
  // truth {0,0,0,1,1,2,2,2,2}, predicted {0,0,1,1,2,2,2,0,2}:
  // (0,0)=2 (0,1)=1 (1,1)=1 (1,2)=1 (2,2)=3 (2,0)=1 -> accuracy 6/9;
  // precision: 2/3, 1/2, 3/4; recall: 2/3, 1/2, 3/4; class 3 absent.
  const std::vector<int> t{0, 0, 0, 1, 1, 2, 2, 2, 2}, p{0, 0, 1, 1, 2, 2, 2, 0, 2};
  auto m = ctxfuse::classify::ConfusionMatrix::from_labels(t, p, 4);
  EXPECT_EQ(m.total(), 9u);
  EXPECT_EQ(m.count(2, 0), 1u);
  EXPECT_EQ(m.count(0, 1), 1u);
  EXPECT_DOUBLE_EQ(m.accuracy(), 6.0 / 9.0);
  EXPECT_DOUBLE_EQ(m.precision(0), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(m.precision(1), 0.5);
  EXPECT_DOUBLE_EQ(m.precision(2), 0.75);
  EXPECT_DOUBLE_EQ(m.recall(0), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(m.recall(1), 0.5);
  EXPECT_DOUBLE_EQ(m.recall(2), 0.75);
  EXPECT_DOUBLE_EQ(m.f1(2), 0.75);
  EXPECT_EQ(m.support(2), 4u);
  EXPECT_TRUE(std::isnan(m.precision(3)));
  EXPECT_TRUE(std::isnan(m.recall(3)));
  EXPECT_THROW(m.add(0, 4), std::out_of_range);
  EXPECT_THROW(m.add(-1, 0), std::out_of_range);
  EXPECT_EQ(m.total(), 9u);  // unchanged by the rejected samples
  EXPECT_THROW((void)m.precision(7), std::out_of_range);
  EXPECT_THROW((void)ctxfuse::classify::ConfusionMatrix::from_labels(t, std::vector<int>{0}, 3), std::invalid_argument);
  EXPECT_THROW(ctxfuse::classify::ConfusionMatrix(0), std::invalid_argument);
  EXPECT_TRUE(std::isnan(ctxfuse::classify::ConfusionMatrix(2).accuracy()));
  // Binary NLOS detection as in paper C: precision = TP/(TP+FP), recall = TP/(TP+FN).
  ctxfuse::classify::ConfusionMatrix b(2);
  for (int i = 0; i < 8; ++i) b.add(1, 1);  // TP 8
  for (int i = 0; i < 2; ++i) b.add(1, 0);  // FN 2
  for (int i = 0; i < 4; ++i) b.add(0, 1);  // FP 4
  for (int i = 0; i < 6; ++i) b.add(0, 0);  // TN 6
  EXPECT_DOUBLE_EQ(b.precision(1), 8.0 / 12.0);
  EXPECT_DOUBLE_EQ(b.recall(1), 0.8);
  EXPECT_DOUBLE_EQ(b.accuracy(), 14.0 / 20.0);
}

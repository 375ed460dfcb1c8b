// UWB NLOS features against hand-computed values.
#include <gtest/gtest.h>

#include <ctxfuse/features/nlos.hpp>

#include <cmath>
#include <limits>

namespace {

using namespace ctxfuse::features;

TEST(NlosFeatures, RangeRateAndConsistencyError) {
  NlosFeatureExtractor ex;
  NlosFeatures f;
  EXPECT_EQ(ex.push({10.0, 20.0, -80.0, -82.5}, 5.0, f), NlosFeatureStatus::first_sample);
  EXPECT_TRUE(std::isnan(f.range_rate_mps));
  EXPECT_DOUBLE_EQ(f.rssi_minus_first_path_db, 2.5);
  // 0.1 s later the range grew by 0.8 m while the car moved 5 m/s * 0.1 s = 0.5 m.
  ASSERT_EQ(ex.push({10.1, 20.8}, 5.0, f), NlosFeatureStatus::ok);
  EXPECT_NEAR(f.range_change_m, 0.8, 1e-12);
  EXPECT_NEAR(f.range_rate_mps, 8.0, 1e-9);
  EXPECT_NEAR(f.travelled_distance_m, 0.5, 1e-9);
  EXPECT_NEAR(f.consistency_error_m, 0.3, 1e-9);
  EXPECT_EQ(f.vehicle_speed_mps, 5.0);
  EXPECT_TRUE(std::isnan(f.rssi_minus_first_path_db));  // not reported on this sample
  // Explicit travelled distance; a shrinking range uses |d_rho|.
  ASSERT_EQ(ex.push({10.3, 20.2}, 1.0, 0.25, f), NlosFeatureStatus::ok);
  EXPECT_NEAR(f.range_rate_mps, -3.0, 1e-9);
  EXPECT_NEAR(f.consistency_error_m, 0.6 - 0.25, 1e-9);
}

TEST(NlosFeatures, BadInputKeepsThePreviousSample) {
  NlosFeatureExtractor ex;
  NlosFeatures f;
  ASSERT_EQ(ex.push({1.0, 10.0}, 0.0, f), NlosFeatureStatus::first_sample);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(ex.push({nan, 10.0}, 0.0, f), NlosFeatureStatus::non_finite_time);
  EXPECT_EQ(ex.push({2.0, nan}, 0.0, f), NlosFeatureStatus::non_finite_range);
  EXPECT_EQ(ex.push({2.0, -1.0}, 0.0, f), NlosFeatureStatus::negative_range);
  EXPECT_EQ(ex.push({2.0, 5e3}, 0.0, f), NlosFeatureStatus::range_too_large);
  EXPECT_EQ(ex.push({1.0, 10.0}, 0.0, f), NlosFeatureStatus::time_not_increasing);
  EXPECT_EQ(ex.push({2.0, 10.0}, -1.0, f), NlosFeatureStatus::invalid_speed);
  EXPECT_EQ(ex.push({2.0, 10.0}, nan, f), NlosFeatureStatus::invalid_speed);
  EXPECT_EQ(ex.push({2.0, 10.0}, 1.0, -0.5, f), NlosFeatureStatus::invalid_distance);
  // Still referenced to the t = 1 sample.
  ASSERT_EQ(ex.push({2.0, 11.0}, 0.0, f), NlosFeatureStatus::ok);
  EXPECT_NEAR(f.range_rate_mps, 1.0, 1e-12);
}

TEST(RangeWindowFeatures, CausalMeanAndStd) {
  RangeWindowFeatures<8> w(3);
  RangeWindowFeatures<8>::Output o;
  ASSERT_TRUE(w.push(0.1, -80, -81, o));
  EXPECT_EQ(o.samples, 1);
  EXPECT_DOUBLE_EQ(o.residual_std_m, 0.0);
  ASSERT_TRUE(w.push(0.3, -82, -82, o));
  EXPECT_NEAR(o.residual_mean_m, 0.2, 1e-15);
  EXPECT_NEAR(o.residual_std_m, 0.1, 1e-15);
  ASSERT_TRUE(w.push(0.2, -84, -86, o));
  EXPECT_NEAR(o.rssi_mean_dbm, -82.0, 1e-12);
  EXPECT_NEAR(o.rssi_minus_first_path_mean_db, (1 + 0 + 2) / 3.0, 1e-12);
  // Fourth value pushes out the first: residuals {0.3, 0.2, 0.6}
  ASSERT_TRUE(w.push(0.6, -80, -80, o));
  EXPECT_EQ(o.samples, 3);
  EXPECT_NEAR(o.residual_mean_m, 1.1 / 3.0, 1e-12);
  const double m = 1.1 / 3.0;
  EXPECT_NEAR(o.residual_std_m, std::sqrt(((0.3 - m) * (0.3 - m) + (0.2 - m) * (0.2 - m) + (0.6 - m) * (0.6 - m)) / 3.0),
              1e-12);
  const auto before = o;
  EXPECT_FALSE(w.push(-std::numeric_limits<double>::infinity(), -80, -80, o));
  EXPECT_EQ(o.residual_mean_m, before.residual_mean_m);
  EXPECT_THROW(RangeWindowFeatures<8>(9), std::invalid_argument);
}

}  // namespace

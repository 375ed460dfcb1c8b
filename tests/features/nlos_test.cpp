// UWB NLOS features against hand-computed values.
#include <gtest/gtest.h>

#include <ctxfuse/features/dw1000.hpp>
#include <ctxfuse/features/nlos.hpp>

#include <cmath>
#include <limits>

namespace {

using namespace ctxfuse::features;
using ctxfuse::Problem;

TEST(NlosFeatures, RangeRateAndConsistencyError) {
  NlosFeatureExtractor ex;
  NlosFeatures f;
  EXPECT_TRUE(ex.push({10.0, 20.0, -80.0, -82.5}, 5.0, f).accepted());
  EXPECT_FALSE(f.has_previous_sample);
  EXPECT_TRUE(std::isnan(f.range_rate_mps));
  EXPECT_DOUBLE_EQ(f.rssi_minus_first_path_db, 2.5);
  // 0.1 s later the range grew by 0.8 m while the car moved 5 m/s * 0.1 s = 0.5 m.
  ASSERT_TRUE(ex.push({10.1, 20.8}, 5.0, f).accepted());
  EXPECT_TRUE(f.has_previous_sample);
  EXPECT_NEAR(f.range_change_m, 0.8, 1e-12);
  EXPECT_NEAR(f.range_rate_mps, 8.0, 1e-9);
  EXPECT_NEAR(f.travelled_distance_m, 0.5, 1e-9);
  EXPECT_NEAR(f.consistency_error_m, 0.3, 1e-9);
  EXPECT_EQ(f.vehicle_speed_mps, 5.0);
  EXPECT_TRUE(std::isnan(f.rssi_minus_first_path_db));  // not reported on this sample
  // Explicit travelled distance; a shrinking range uses |d_rho|.
  ASSERT_TRUE(ex.push({10.3, 20.2}, 1.0, 0.25, f).accepted());
  EXPECT_NEAR(f.range_rate_mps, -3.0, 1e-9);
  EXPECT_NEAR(f.consistency_error_m, 0.6 - 0.25, 1e-9);
}

TEST(NlosFeatures, BadInputKeepsThePreviousSample) {
  NlosFeatureExtractor ex;
  NlosFeatures f;
  ASSERT_TRUE(ex.push({1.0, 10.0, -80.0, -81.0}, 0.0, f).accepted());
  ASSERT_FALSE(f.has_previous_sample);
  const NlosFeatures before = f;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto refused = [&](ctxfuse::Status st, Problem expected) {
    EXPECT_EQ(st.outcome, ctxfuse::Outcome::invalid_input);
    EXPECT_EQ(st.problem, expected) << ctxfuse::describe(st.problem);
  };
  refused(ex.push({nan, 10.0}, 0.0, f), Problem::non_finite_time);
  refused(ex.push({2.0, nan}, 0.0, f), Problem::non_finite_measurement);
  refused(ex.push({2.0, -1.0}, 0.0, f), Problem::measurement_out_of_domain);
  refused(ex.push({2.0, 5e3}, 0.0, f), Problem::measurement_magnitude);
  refused(ex.push({1.0, 10.0}, 0.0, f), Problem::out_of_order_time);
  refused(ex.push({2.0, 10.0}, -1.0, f), Problem::input_out_of_domain);
  refused(ex.push({2.0, 10.0}, 150.0, f), Problem::input_out_of_domain);  // above max_speed_mps
  refused(ex.push({2.0, 10.0}, nan, f), Problem::non_finite_input);
  refused(ex.push({2.0, 10.0}, 1.0, -0.5, f), Problem::input_out_of_domain);
  refused(ex.push({2.0, 10.0}, 1.0, nan, f), Problem::non_finite_input);
  // `out` untouched by every refusal.
  EXPECT_FALSE(f.has_previous_sample);
  EXPECT_EQ(f.rssi_minus_first_path_db, before.rssi_minus_first_path_db);
  EXPECT_EQ(f.vehicle_speed_mps, before.vehicle_speed_mps);
  EXPECT_TRUE(std::isnan(f.range_rate_mps));
  // Still referenced to the t = 1 sample.
  ASSERT_TRUE(ex.push({2.0, 11.0}, 0.0, f).accepted());
  EXPECT_TRUE(f.has_previous_sample);
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

TEST(Dw1000Features, ManualFormulasByHand) {
  // First data row of the Hanyang recording LOS/height_50.0cm/10m.csv.
  Dw1000Diagnostics d;
  d.range_m = 10.168694;
  d.fp_amp1 = 14305, d.fp_amp2 = 15276, d.fp_amp3 = 14270;
  d.cir_power = 6491, d.rxpacc = 230, d.std_noise = 52;
  Dw1000Features f;
  ASSERT_TRUE(dw1000_features(d, f).accepted());
  // 6491 * 2^17 = 850788352; / 230^2 = 16082.956...; 10 log10 = 42.0637; - 121.74
  EXPECT_NEAR(f.rx_power_dbm, 10.0 * std::log10(850788352.0 / 52900.0) - 121.74, 1e-12);
  EXPECT_NEAR(f.rx_power_dbm, -79.68, 0.005);  // the chip's RSSI logged on that row
  // 14305^2 + 15276^2 + 14270^2 = 641622101
  EXPECT_NEAR(f.fp_power_dbm, 10.0 * std::log10(641622101.0 / 52900.0) - 121.74, 1e-12);
  EXPECT_NEAR(f.rx_minus_fp_db, f.rx_power_dbm - f.fp_power_dbm, 1e-12);
  EXPECT_NEAR(f.noise_dbm, 10.0 * std::log10(2704.0 / 52900.0) - 121.74, 1e-12);
  EXPECT_EQ(f.range_m, d.range_m);
  // 16 MHz PRF: the constant 113.77 instead of 121.74, so every power rises by 7.97 dB.
  Dw1000Diagnostics d16 = d;
  d16.prf_mhz = 16;
  Dw1000Features f16;
  ASSERT_TRUE(dw1000_features(d16, f16).accepted());
  EXPECT_NEAR(f16.rx_power_dbm - f.rx_power_dbm, 7.97, 1e-9);
  EXPECT_NEAR(f16.rx_minus_fp_db, f.rx_minus_fp_db, 1e-9);
  // A doubled preamble accumulation with doubled amplitudes (C scales with N^2) is the same frame.
  Dw1000Diagnostics twice = d;
  twice.rxpacc *= 2, twice.fp_amp1 *= 2, twice.fp_amp2 *= 2, twice.fp_amp3 *= 2, twice.cir_power *= 4, twice.std_noise *= 2;
  Dw1000Features f2;
  ASSERT_TRUE(dw1000_features(twice, f2).accepted());
  for (std::size_t k = 0; k < kDw1000FeatureCount; ++k) EXPECT_NEAR(f2.values()[k], f.values()[k], 1e-9) << kDw1000FeatureNames[k];
  // Rejections leave `out` alone.
  const auto before = f.values();
  Dw1000Diagnostics bad = d;
  bad.prf_mhz = 32;
  EXPECT_EQ(dw1000_features(bad, f).problem, Problem::invalid_prf);
  bad = d, bad.rxpacc = 0;
  EXPECT_EQ(dw1000_features(bad, f).problem, Problem::invalid_rxpacc);
  bad = d, bad.cir_power = 0;
  EXPECT_EQ(dw1000_features(bad, f).problem, Problem::non_positive_power);
  bad = d, bad.fp_amp2 = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(dw1000_features(bad, f).problem, Problem::non_finite_measurement);
  EXPECT_EQ(f.values(), before);
}

}  // namespace

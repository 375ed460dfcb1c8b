// Scene features against hand-computed epochs.
#include <gtest/gtest.h>

#include <ctxfuse/features/gnss_scene.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace {

using namespace ctxfuse::features;
using ctxfuse::Problem;
using F = GnssSceneFeature;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(GnssScene, AzimuthVacancyHandlesWrapAndElevationMask) {
  std::vector<double> scratch(8);
  // 10-60 deg mask keeps azimuths 350, 20, 100, 200; 5 deg and 70 deg satellites ignored.
  const std::vector<SatelliteObservation> sats{
      {1, 30, 350, 40}, {2, 15, 20, 40}, {3, 45, 100, 40}, {4, 60, 200, 40}, {5, 5, 280, 40}, {6, 70, 290, 40}};
  // gaps: 20->100 = 80, 100->200 = 100, 200->350 = 150, 350->20 (across 0) = 30
  EXPECT_DOUBLE_EQ(azimuth_vacancy(sats, 10, 60, scratch), 150.0);
  // Largest gap across north: satellites at 100 and 250 only -> 250->100 via 0 = 210.
  const std::vector<SatelliteObservation> two{{1, 30, 250, 40}, {2, 30, 100, 40}};
  EXPECT_DOUBLE_EQ(azimuth_vacancy(two, 10, 60, scratch), 210.0);
  // Negative / over-360 azimuths are wrapped: -10 = 350, 370 = 10 -> gaps 20 and 340.
  const std::vector<SatelliteObservation> wrapped{{1, 30, -10, 40}, {2, 30, 370, 40}};
  EXPECT_NEAR(azimuth_vacancy(wrapped, 10, 60, scratch), 340.0, 1e-12);
  // One or zero satellites in the mask: 360; untracked satellites (NaN C/N0) do not count.
  const std::vector<SatelliteObservation> one{{1, 30, 100, 40}, {2, 30, 200, kNaN}};
  EXPECT_DOUBLE_EQ(azimuth_vacancy(one, 10, 60, scratch), 360.0);
}

TEST(GnssScene, PdopOfKnownGeometry) {
  // Zenith + three on the horizon 120 deg apart: G^T G = diag(1.5, 1.5, [[1, 1], [1, 4]]),
  // so PDOP^2 = 1/1.5 + 1/1.5 + 4/3 = 8/3.
  const std::vector<SatelliteObservation> sats{{1, 90, 0, 40}, {2, 0, 0, 40}, {3, 0, 120, 40}, {4, 0, 240, 40}};
  EXPECT_NEAR(pdop_from_geometry(sats), std::sqrt(8.0 / 3.0), 1e-12);
  // Three satellites: no solution.
  EXPECT_TRUE(std::isnan(pdop_from_geometry(std::span(sats).first(3))));
  // All at one point of the sky: singular.
  const std::vector<SatelliteObservation> same{{1, 30, 10, 40}, {2, 30, 10, 40}, {3, 30, 10, 40}, {4, 30, 10, 40}};
  EXPECT_TRUE(std::isnan(pdop_from_geometry(same)));
}

TEST(GnssScene, FeaturesOfHandComputedEpochs) {
  GnssSceneExtractor<16, 8> ex;
  GnssSceneFeatures f;
  // t = 0: three tracked satellites + one untracked; receiver PDOP 2.0.
  const std::vector<SatelliteObservation> e0{{1, 20, 10, 40}, {2, 40, 100, 44}, {3, 60, 300, 48}, {4, 50, 200, kNaN}};
  ASSERT_TRUE(ex.push({0.0, e0, 2.0}, f).accepted());
  EXPECT_EQ(f[F::satellite_count], 3);
  EXPECT_EQ(f[F::pdop], 2.0);
  EXPECT_DOUBLE_EQ(f[F::mean_cn0], 44.0);
  EXPECT_DOUBLE_EQ(f[F::mean_elevation], 40.0);
  EXPECT_DOUBLE_EQ(f[F::count_std], 0.0);
  EXPECT_DOUBLE_EQ(f[F::pdop_std], 0.0);
  EXPECT_EQ(f[F::mean_cn0_std], -1.0);  // one epoch: no C/N0 history yet -> fill
  // azimuths 10, 100, 300: gaps 90, 200, 70 (300 -> 10 across north)
  EXPECT_DOUBLE_EQ(f[F::azimuth_vacancy], 200.0);

  // t = 1: satellite 1 at 42, 2 at 44, new satellite 5; PDOP 3.0.
  const std::vector<SatelliteObservation> e1{{1, 20, 10, 42}, {2, 40, 100, 44}, {5, 30, 190, 38}, {3, 60, 300, 50}};
  ASSERT_TRUE(ex.push({1.0, e1, 3.0}, f).accepted());
  EXPECT_EQ(f[F::satellite_count], 4);
  EXPECT_DOUBLE_EQ(f[F::mean_cn0], (42 + 44 + 38 + 50) / 4.0);
  EXPECT_DOUBLE_EQ(f[F::count_std], 0.5);   // counts {3, 4}
  EXPECT_DOUBLE_EQ(f[F::pdop_std], 0.5);    // pdops {2, 3}
  // per-satellite C/N0 std over the two epochs: sat1 {40,42} -> 1, sat2 {44,44} -> 0,
  // sat3 {48,50} -> 1, sat5 single value -> skipped; mean = 2/3
  EXPECT_NEAR(f[F::mean_cn0_std], 2.0 / 3.0, 1e-12);

  // t = 2, 3, 4: satellite 1 only (C/N0 44, 40, 40) -> sat1 history over the last 4 epochs:
  // t=1..4: {42, 44, 40, 40}, mean 41.5, population std sqrt((0.25+6.25+2.25+2.25)/4)
  const std::vector<SatelliteObservation> s44{{1, 20, 10, 44}}, s40{{1, 20, 10, 40}};
  ASSERT_TRUE(ex.push({2.0, s44}, f).accepted());
  ASSERT_TRUE(ex.push({3.0, s40}, f).accepted());
  ASSERT_TRUE(ex.push({4.0, s40}, f).accepted());
  EXPECT_NEAR(f[F::mean_cn0_std], std::sqrt(11.0 / 4.0), 1e-12);
  // Window (0, 4]: epochs t = 1..4 with counts {4, 1, 1, 1}: mean 1.75, std sqrt(27/16)
  EXPECT_NEAR(f[F::count_std], std::sqrt((2.25 * 2.25 + 3 * 0.75 * 0.75) / 4.0), 1e-12);
  EXPECT_EQ(f[F::pdop], -1.0);       // one satellite, no receiver PDOP -> fill
  EXPECT_DOUBLE_EQ(f[F::pdop_std], 0.0);  // only t = 1 has a PDOP inside the window
  EXPECT_DOUBLE_EQ(f[F::azimuth_vacancy], 360.0);
}

TEST(GnssScene, IndoorEpochFillsAndBadInputLeavesStateUnchanged) {
  GnssSceneConfig cfg;
  cfg.fill_value = -5.0;
  GnssSceneExtractor<4, 8> ex(cfg);
  GnssSceneFeatures f;
  ASSERT_TRUE(ex.push({0.0, {}}, f).accepted());
  EXPECT_EQ(f[F::satellite_count], 0.0);
  for (int k = 1; k < kGnssSceneFeatureCount; ++k) EXPECT_EQ(f[k], -5.0) << k;

  const GnssSceneFeatures before = f;
  const std::vector<SatelliteObservation> ok{{1, 20, 10, 40}};
  EXPECT_EQ(ex.push({0.0, ok}, f).problem, Problem::out_of_order_time);
  EXPECT_EQ(ex.push({kNaN, ok}, f).problem, Problem::non_finite_time);
  const std::vector<SatelliteObservation> bad_el{{1, 95, 10, 40}}, bad_cn0{{1, 20, 10, -3}}, dup{{1, 20, 10, 40}, {1, 30, 50, 40}};
  EXPECT_EQ(ex.push({1.0, bad_el}, f).problem, Problem::invalid_elevation);
  EXPECT_EQ(ex.push({1.0, bad_cn0}, f).problem, Problem::invalid_cn0);
  EXPECT_EQ(ex.push({1.0, dup}, f).problem, Problem::duplicate_satellite);
  EXPECT_EQ(ex.push({1.0, ok, -2.0}, f).problem, Problem::invalid_dop);
  const std::vector<SatelliteObservation> five(5, SatelliteObservation{1, 20, 10, 40});
  EXPECT_EQ(ex.push({1.0, five}, f).problem, Problem::measurement_count_above_capacity);
  EXPECT_EQ(f, before);
  // The rejected epochs left no trace: t = 1 is still accepted and its window holds {0, 1}.
  ASSERT_TRUE(ex.push({1.0, ok}, f).accepted());
  EXPECT_DOUBLE_EQ(f[F::count_std], 0.5);
}

TEST(GnssScene, BatchMatchesStreamingAndNamesTheBadEpoch) {
  const std::vector<SatelliteObservation> a{{1, 20, 10, 40}, {2, 40, 100, 44}}, b{{1, 20, 12, 41}};
  const std::vector<GnssEpoch> epochs{{0.0, a}, {1.0, b}, {2.0, a}};
  const auto batch = gnss_scene_features(std::span<const GnssEpoch>(epochs));
  ASSERT_TRUE(batch.status.accepted());
  ASSERT_EQ(batch.features.size(), epochs.size());
  GnssSceneExtractor<> ex;
  for (std::size_t i = 0; i < epochs.size(); ++i) {
    GnssSceneFeatures f;
    ASSERT_TRUE(ex.push(epochs[i], f).accepted());
    EXPECT_EQ(f, batch.features[i]);
  }
  const std::vector<GnssEpoch> backwards{{1.0, a}, {0.5, a}};
  const auto refused = gnss_scene_features(std::span<const GnssEpoch>(backwards));
  EXPECT_EQ(refused.status.outcome, ctxfuse::Outcome::invalid_input);
  EXPECT_EQ(refused.status.problem, Problem::out_of_order_time);
  EXPECT_EQ(refused.refused_at, 1u);
  EXPECT_TRUE(refused.features.empty());
}

TEST(GnssScene, WindowsOutOfRangeAreNamedAndRefusedAtConstruction) {
  GnssSceneConfig c;
  ASSERT_TRUE(c.check().ok());
  c.cn0_window_s = std::numeric_limits<double>::infinity();
  EXPECT_EQ(c.check().problem, Problem::invalid_setting);
  EXPECT_EQ(c.check().what, "cn0_window_s must be finite and > 0");
  try {
    GnssSceneExtractor<> ex(c);
    FAIL() << "expected the constructor to refuse";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "GnssSceneExtractor: cn0_window_s must be finite and > 0");
  }
  c = {};
  c.window_s = 0.0;
  EXPECT_EQ(c.check().what, "window_s must be finite and > 0");
}

TEST(GnssScene, WindowDropsEpochsOlderThanFourSeconds) {
  GnssSceneExtractor<4, 16> ex;
  GnssSceneFeatures f;
  const std::vector<SatelliteObservation> one{{1, 20, 10, 40}},
      two{{1, 20, 10, 40}, {2, 20, 50, 40}};
  ASSERT_TRUE(ex.push({0.0, two}, f).accepted());
  ASSERT_TRUE(ex.push({1.0, one}, f).accepted());
  EXPECT_DOUBLE_EQ(f[F::count_std], 0.5);
  ASSERT_TRUE(ex.push({4.5, one}, f).accepted());  // window (0.5, 4.5]: t = 1, 4.5
  EXPECT_DOUBLE_EQ(f[F::count_std], 0.0);
}

TEST(GnssScene, UnknownGeometryCountsInCn0FeaturesOnly) {
  GnssSceneExtractor<16, 8> ex;
  GnssSceneFeatures f;
  // Satellites 3 (elevation and azimuth unknown) and 5 (azimuth unknown) are tracked without
  // geometry: they count in the satellite count and the C/N0 features only.
  const std::vector<SatelliteObservation> e0{
      {1, 20, 10, 40}, {2, 40, 100, 44}, {3, kNaN, kNaN, 48}, {4, 60, 300, 36}, {5, 30, kNaN, 50}};
  ASSERT_TRUE(ex.push({0.0, e0}, f).accepted());
  EXPECT_EQ(f[F::satellite_count], 5);
  EXPECT_DOUBLE_EQ(f[F::mean_cn0], (40 + 44 + 48 + 36 + 50) / 5.0);
  EXPECT_DOUBLE_EQ(f[F::mean_elevation], (20 + 40 + 60) / 3.0);
  EXPECT_DOUBLE_EQ(f[F::azimuth_vacancy], 200.0);  // azimuths 10, 100, 300 as above
  EXPECT_EQ(f[F::pdop], -1.0);                     // 3 satellites with geometry: no PDOP
  // t = 1: satellite 3 at 50 dB-Hz: its C/N0 std {48, 50} = 1 counts; the others unchanged (0).
  std::vector<SatelliteObservation> e1 = e0;
  e1[2].cn0_dbhz = 50;
  ASSERT_TRUE(ex.push({1.0, e1}, f).accepted());
  EXPECT_NEAR(f[F::mean_cn0_std], 1.0 / 5.0, 1e-12);
  // With a fourth satellite of known geometry the computed PDOP is that of the four only.
  const std::vector<SatelliteObservation> known{{1, 90, 0, 40}, {2, 0, 0, 40}, {3, 0, 120, 40}, {4, 0, 240, 40}};
  std::vector<SatelliteObservation> mixed = known;
  mixed.push_back({9, kNaN, 45, 40});
  ASSERT_TRUE(ex.push({2.0, mixed}, f).accepted());
  EXPECT_NEAR(f[F::pdop], std::sqrt(8.0 / 3.0), 1e-12);
  EXPECT_EQ(f[F::satellite_count], 5);
  // Infinite values are still errors; only NaN means unknown.
  const std::vector<SatelliteObservation> inf_el{{1, std::numeric_limits<double>::infinity(), 10, 40}};
  EXPECT_EQ(ex.push({3.0, inf_el}, f).problem, Problem::invalid_elevation);
}

// The same sky sampled at 1 Hz and 5 Hz: C/N0 and satellite count change once per second (value
// of second ceil(t)), so at whole seconds every window in seconds holds the same values, 5 times
// each at 5 Hz. Windows counted in epochs would cover 0.8 s at 5 Hz and differ.
std::vector<SatelliteObservation> sky(double t) {
  const int k = static_cast<int>(std::ceil(t - 1e-9));
  std::vector<SatelliteObservation> s{{1, 20, 10, 40.0 + (k % 3)}, {2, 40, 100, 44.0 - (k % 4)}, {3, 60, 300, 38.0 + (k % 5)},
                                      {4, 35, 200, 42.0}};
  if (k % 2 == 0) s.push_back({5, 15, 250, 30.0 + k % 7});
  return s;
}

TEST(GnssScene, WindowsInSecondsMatchAt1And5Hz) {
  GnssSceneExtractor<8, 32> slow, fast;
  GnssSceneFeatures fs, ff;
  int compared = 0;
  for (int step = 1; step <= 5 * 20; ++step) {
    const double t = 0.2 * step;
    const auto sats = sky(t);
    ASSERT_TRUE(fast.push({t, sats}, ff).accepted());
    if (step % 5 != 0) continue;
    ASSERT_TRUE(slow.push({t, sats}, fs).accepted());
    if (t < 4.0) continue;  // both windows full
    for (int k = 0; k < kGnssSceneFeatureCount; ++k) EXPECT_NEAR(ff[k], fs[k], 1e-12) << "feature " << k << " at t " << t;
    ++compared;
  }
  EXPECT_EQ(compared, 17);
  EXPECT_GT(fs[F::mean_cn0_std], 0.1);  // the windows do see variation
  EXPECT_GT(fs[F::count_std], 0.1);
}

}  // namespace

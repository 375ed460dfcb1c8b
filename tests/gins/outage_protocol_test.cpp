// The outage evaluation (studies/outage_protocol.hpp) and the GNSS schedule of the pipeline
// (pipelines/gins/gnss_schedule.hpp) on hand-made inputs, checked exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "ctxfuse/studies/outage_protocol.hpp"

namespace {
using namespace ctxfuse;
using pipelines::gins::OutageWindow;

TEST(GinsOutageProtocol, StandardWindowsOnTheDrivesSpan) {
  // The drive's first and last GNSS epochs are 549 s apart: 40 + 45 k + 15 <= 549 - 30 for
  // k = 0..10 (k = 11 would end at 550), i.e. 11 windows.
  const double t0 = 1000.5;
  const auto w = pipelines::gins::outage_windows(ctxfuse::studies::standard_outages(), t0, t0 + 549.0);
  ASSERT_EQ(w.size(), 11u);
  for (std::size_t k = 0; k < w.size(); ++k) {
    EXPECT_DOUBLE_EQ(w[k].start, t0 + 40.0 + 45.0 * static_cast<double>(k));
    EXPECT_DOUBLE_EQ(w[k].end, w[k].start + 15.0);
  }
  // The 11th window ends 505 s in: it needs the last epoch at least 535 s after the first.
  EXPECT_EQ(pipelines::gins::outage_windows(ctxfuse::studies::standard_outages(), t0, t0 + 535.0).size(), 11u);
  EXPECT_EQ(pipelines::gins::outage_windows(ctxfuse::studies::standard_outages(), t0, t0 + 534.9).size(), 10u);
  // Half-open: the start is inside, the end is not.
  EXPECT_TRUE(w[0].contains(t0 + 40.0));
  EXPECT_FALSE(w[0].contains(t0 + 55.0));
  EXPECT_TRUE(pipelines::gins::outage_windows({}, t0, t0 + 549.0).empty());
}

TEST(GinsOutageProtocol, DecimationKeepsOneFixPerPeriodFromTheFirst) {
  pipelines::gins::Decimator d(1.0);
  // 4 Hz stamps at .499/.749/...: keeps 0.499, 1.499, 2.499; after a missing 3.499, 3.749.
  const std::vector<double> t{0.499, 0.749, 0.999, 1.249, 1.499, 1.749, 1.999, 2.249, 2.499, 2.749, 2.999, 3.249, 3.749, 3.999, 4.249, 4.749};
  std::vector<double> kept;
  for (double x : t)
    if (d.keep(x)) kept.push_back(x);
  EXPECT_EQ(kept, (std::vector<double>{0.499, 1.499, 2.499, 3.749, 4.749}));
  pipelines::gins::Decimator all(0.0);
  for (double x : t) EXPECT_TRUE(all.keep(x));
}

TEST(GinsOutageProtocol, ReferenceIsTheRtkFixedEpochsOnly) {
  std::vector<messages::GnssFix> fixes(4);
  const messages::FixQuality q[] = {messages::FixQuality::fixed, messages::FixQuality::floating, messages::FixQuality::single, messages::FixQuality::fixed};
  for (int i = 0; i < 4; ++i) {
    fixes[i].t = i;
    fixes[i].frame = messages::PositionFrame::geodetic;
    fixes[i].position = {40.0 + i, -105.0, 1600.0};
    fixes[i].quality = q[i];
  }
  const auto ref = ctxfuse::studies::rtk_fixed_reference(fixes);
  ASSERT_EQ(ref.size(), 2u);
  EXPECT_EQ(ref[0].t, 0.0);
  EXPECT_EQ(ref[1].t, 3.0);
  EXPECT_DOUBLE_EQ(ref[1].lat, 43.0 * 3.14159265358979323846 / 180.0);
}

TEST(GinsOutageProtocol, InterpolatedErrorsRmsAndMax) {
  // Trajectory at 0, 2, 4 s; reference at 1, 2, 3 s inside the window [1, 4) and at 5 s
  // outside it. The trajectory is 3 m north of the reference at 0 s and 1 m at 2 s (so 2 m
  // at the interpolated 1 s), and 4 m east at 4 s (2 m east + 0.5 m north at 3 s).
  const double lat = 0.7, lon = -1.8;
  const Eigen::Vector3d per = earth::ned_per_llh(lat, 0.0);
  const double n = 1.0 / per(0), e = 1.0 / per(1);  // radians per metre
  const std::vector<ctxfuse::studies::TimedLatLon> traj{{0.0, lat + 3 * n, lon}, {2.0, lat + 1 * n, lon}, {4.0, lat, lon + 4 * e}};
  const std::vector<ctxfuse::studies::TimedLatLon> ref{{1.0, lat, lon}, {2.0, lat, lon}, {3.0, lat, lon}, {5.0, lat, lon}};
  const std::vector<OutageWindow> windows{{1.0, 4.0}};
  const auto r = ctxfuse::studies::outage_errors(traj, ref, windows);
  ASSERT_EQ(r.epochs, 3u);
  EXPECT_EQ(r.unscored, 0u);
  const double e1 = 2.0, e2 = 1.0, e3 = std::hypot(0.5, 2.0);
  EXPECT_NEAR(r.rms, std::sqrt((e1 * e1 + e2 * e2 + e3 * e3) / 3.0), 1e-9);
  EXPECT_NEAR(r.max, e3, 1e-9);
  ASSERT_EQ(r.outages.size(), 1u);
  EXPECT_EQ(r.outages[0].epochs, 3u);
  // A window past the trajectory's end: its reference epoch is counted as unscored.
  const std::vector<OutageWindow> late{{4.5, 6.0}};
  const auto r2 = ctxfuse::studies::outage_errors(traj, ref, late);
  EXPECT_EQ(r2.epochs, 0u);
  EXPECT_EQ(r2.unscored, 1u);
}

}  // namespace

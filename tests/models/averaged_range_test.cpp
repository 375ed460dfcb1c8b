// The averaged, biased range (models/averaged_range.hpp) against its definition written out
// (the mean of n ranges from the positions j periods back, plus the anchor's bias) and its
// analytic Jacobian against central differences. Ceres' automatic Jacobian of the same model
// is in tests/factors/ceres_equality_test.cpp.
#include <gtest/gtest.h>

#include <cmath>

#include "ctxfuse/models/averaged_range.hpp"
#include "ctxfuse/testing/jacobians.hpp"

namespace {
using namespace ctxfuse;
using ctxfuse::testing::central_jacobian;

using BiasedL = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>, StateBlock<"b", 3>>;

Vector<7> state() {
  Vector<7> x;
  x << 12.0, -7.5, 1.2, -0.8, 0.05, -0.03, 0.11;
  return x;
}

models::AveragedRangeWithBias<BiasedL> model(const Eigen::Vector3d& anchor, int samples, int bias_slot) {
  models::AveragedRangeWithBias<BiasedL> m;
  m.anchor = anchor;
  m.tag_height = 1.0;
  m.samples = samples;
  m.period_s = 0.1;
  m.bias_slot = bias_slot;
  return m;
}

double range(double x, double y, const Eigen::Vector3d& a, double h) {
  return std::sqrt((x - a.x()) * (x - a.x()) + (y - a.y()) * (y - a.y()) + (h - a.z()) * (h - a.z()));
}

TEST(AveragedRange, IsTheMeanOfTheRangesFromThePositionsBackPlusTheBias) {
  auto m = model({2.5, 0.87, 1.97}, 3, 2);
  const Vector<7> x = state();
  // Written out: positions now, 0.1 s and 0.2 s back under the state's velocity.
  const double expected = (range(12.0, -7.5, m.anchor, 1.0) + range(12.0 - 0.12, -7.5 + 0.08, m.anchor, 1.0) +
                           range(12.0 - 0.24, -7.5 + 0.16, m.anchor, 1.0)) / 3.0 + 0.11;
  EXPECT_NEAR(m.predict(x, nullptr)(0), expected, 1e-12);
  EXPECT_NEAR(m.value<double>(x)(0), expected, 1e-12);
  // One sample and no bias slot: the range from the tag's height now.
  m.samples = 1;
  m.bias_slot = -1;
  EXPECT_NEAR(m.predict(x, nullptr)(0), range(12.0, -7.5, m.anchor, 1.0), 1e-12);
}

TEST(AveragedRange, AnalyticJacobianEqualsCentralDifferences) {
  for (int samples : {1, 3, 5})
    for (int slot : {-1, 0, 2}) {
      const auto m = model({-3.0, 4.0, 0.5}, samples, slot);
      const Vector<7> x = state();
      Matrix<1, 7> H;
      m.predict(x, &H);
      const auto f = [&](const Vector<7>& s) { return m.predict(s, nullptr); };
      // h = 1e-4: ranges of ~15 m leave 1e-9 of rounding at the default 1e-6 step.
      EXPECT_LT((H - central_jacobian<1, 7>(f, x, 1e-4)).cwiseAbs().maxCoeff(), 1e-9) << samples << " samples, slot " << slot;
      // The velocity columns vanish with one sample: the range now does not see it.
      const double velocity_columns = H.segment<2>(2).norm();
      if (samples == 1) {
        EXPECT_EQ(velocity_columns, 0.0);
      } else {
        EXPECT_GT(velocity_columns, 0.01);
      }
    }
}

TEST(AveragedRange, OnTheAnchorTheRowStaysFinite) {
  const auto m = model({1.0, 2.0, 1.0}, 1, 1);
  Vector<7> x = Vector<7>::Zero();
  x(0) = 1.0;
  x(1) = 2.0;
  Matrix<1, 7> H;
  EXPECT_NEAR(m.predict(x, &H)(0), 0.0, 1e-15);
  EXPECT_TRUE(H.allFinite());
  EXPECT_EQ(H(0, 5), 1.0);  // the bias still enters
  EXPECT_EQ(H.head<4>().norm(), 0.0);
}

}  // namespace

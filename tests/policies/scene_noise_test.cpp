// Scene-adaptive GNSS noise (policies/scene_noise.hpp) against the scene paper's eq. 20-21
// written out by hand (WGS-84 radii from their textbook formulas, not earth::radii), its
// refusals of bad probabilities (R untouched), and R used by the geodetic GNSS update: the
// posterior position variance in metres equals the scalar Kalman formula P s^2 / (P + s^2).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/models/ins_nav.hpp"
#include "ctxfuse/models/ins_updates.hpp"
#include "ctxfuse/policies/scene_noise.hpp"

namespace {
using namespace ctxfuse;
using policies::FixedGnssNoise;
using policies::SceneAdaptiveGnssNoise;
using policies::SceneProbabilities;

constexpr double kDeg = std::numbers::pi / 180.0;
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

// Eq. 21 with the meridian and prime-vertical radii of WGS-84 written out.
Eigen::Matrix3d eq21(double sigma, double lat, double h) {
  const double a = 6378137.0, f = 1.0 / 298.257223563, e2 = f * (2.0 - f);
  const double s2 = std::sin(lat) * std::sin(lat);
  const double M = a * (1.0 - e2) / std::pow(1.0 - e2 * s2, 1.5);
  const double N = a / std::sqrt(1.0 - e2 * s2);
  Eigen::Matrix3d R = Eigen::Matrix3d::Zero();
  R(0, 0) = std::pow(sigma / (M + h), 2);
  R(1, 1) = std::pow(sigma / ((N + h) * std::cos(lat)), 2);
  R(2, 2) = sigma * sigma;
  return R;
}

void expect_relative(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b, double tol) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      if (b(i, j) == 0.0) EXPECT_EQ(a(i, j), 0.0) << i << "," << j;
      else EXPECT_NEAR(a(i, j) / b(i, j), 1.0, tol) << i << "," << j;
    }
}

TEST(SceneNoise, SigmaIsTheProbabilityWeightedSceneSigma) {
  SceneAdaptiveGnssNoise n;
  ASSERT_TRUE(n.valid());
  ASSERT_TRUE(n.observe({0.8, 0.19, 0.01}).accepted());
  EXPECT_NEAR(n.sigma(), 4.5, 1e-14) << "the paper's example";
  ASSERT_TRUE(n.observe({1.0, 0.0, 0.0}).accepted());
  EXPECT_EQ(n.sigma(), 2.0);
  ASSERT_TRUE(n.observe({0.0, 1.0, 0.0}).accepted());
  EXPECT_EQ(n.sigma(), 10.0);
  ASSERT_TRUE(n.observe({0.0, 0.0, 1.0}).accepted());
  EXPECT_EQ(n.sigma(), 100.0);
  // Other scene sigmas.
  SceneAdaptiveGnssNoise m({1.5, 4.0, 30.0});
  const SceneProbabilities p{0.25, 0.6, 0.15};
  ASSERT_TRUE(m.observe(p).accepted());
  EXPECT_NEAR(m.sigma(), 0.25 * 1.5 + 0.6 * 4.0 + 0.15 * 30.0, 1e-14);
}

TEST(SceneNoise, GeodeticRIsEquation21) {
  SceneAdaptiveGnssNoise n;
  ASSERT_TRUE(n.observe({0.8, 0.19, 0.01}).accepted());
  for (double lat_deg : {0.0, 24.85, 37.4, -61.0}) {
    const Eigen::Vector3d llh(lat_deg * kDeg, 102.7 * kDeg, 1890.0);
    expect_relative(n.geodetic(llh), eq21(4.5, llh(0), llh(2)), 1e-12);
    // The same R as the measurement model's own conversion of sigma^2 I.
    expect_relative(n.geodetic(llh), models::geodetic_position_noise(llh, n.ned_covariance()), 1e-12);
  }
  EXPECT_EQ(n.ned_covariance(), Eigen::Matrix3d::Identity() * 4.5 * 4.5);
}

TEST(SceneNoise, InvalidProbabilitiesAreRefusedAndLeaveRAsItWas) {
  SceneAdaptiveGnssNoise n;
  ASSERT_TRUE(n.observe({0.5, 0.3, 0.2}).accepted());  // sigma = 1 + 3 + 20 = 24 m
  const double sigma = n.sigma();
  const Eigen::Vector3d llh(24.85 * kDeg, 102.7 * kDeg, 1890.0);
  const Eigen::Matrix3d R = n.geodetic(llh);
  struct Case {
    SceneProbabilities p;
    Problem problem;
  };
  const Case bad[] = {
      {{kNaN, 0.5, 0.5}, Problem::measurement_noise_non_finite},
      {{0.5, kInf, 0.5}, Problem::measurement_noise_non_finite},
      {{0.5, 0.5, -kInf}, Problem::measurement_noise_non_finite},
      {{1.1, -0.1, 0.0}, Problem::measurement_out_of_domain},     // sums to 1, one negative
      {{0.8, 0.19, 0.02}, Problem::measurement_out_of_domain},    // sums to 1.01
      {{0.0, 0.0, 0.0}, Problem::measurement_out_of_domain},
      {{0.5, 0.5, 2e-6}, Problem::measurement_out_of_domain},     // just outside 1e-6
      {{0.5, 0.5 - 2e-6, 0.0}, Problem::measurement_out_of_domain},
  };
  for (const Case& c : bad) {
    const Status s = n.observe(c.p);
    EXPECT_EQ(s.outcome, Outcome::invalid_input);
    EXPECT_EQ(s.problem, c.problem);
    EXPECT_EQ(n.sigma(), sigma);
    EXPECT_EQ(n.geodetic(llh), R);
  }
  // Inside the stated tolerance: accepted, the weights used as given.
  ASSERT_TRUE(n.observe({0.5, 0.5, 5e-7}).accepted());
  EXPECT_NEAR(n.sigma(), 0.5 * 2.0 + 0.5 * 10.0 + 5e-7 * 100.0, 1e-14);
  // A wider stated tolerance accepts what the default refuses.
  SceneAdaptiveGnssNoise loose({2.0, 10.0, 100.0}, 0.02);
  EXPECT_TRUE(loose.observe({0.8, 0.19, 0.02}).accepted());
  EXPECT_NEAR(loose.sigma(), 1.6 + 1.9 + 2.0, 1e-14);
}

TEST(SceneNoise, BadSceneSigmasAreReported) {
  EXPECT_FALSE(SceneAdaptiveGnssNoise({2.0, 0.0, 100.0}).valid());
  EXPECT_FALSE(SceneAdaptiveGnssNoise({2.0, kNaN, 100.0}).valid());
  EXPECT_FALSE(SceneAdaptiveGnssNoise({2.0, 10.0, 100.0}, -1.0).valid());
  EXPECT_FALSE(FixedGnssNoise(-1.0).valid());
  EXPECT_FALSE(FixedGnssNoise(kNaN).valid());
}

TEST(SceneNoise, FixedPolicyHasTheSameInterfaceAndIgnoresTheScene) {
  FixedGnssNoise f(3.0);
  ASSERT_TRUE(f.valid());
  const Eigen::Vector3d llh(37.4 * kDeg, -122.1 * kDeg, 30.0);
  for (const SceneProbabilities& p : {SceneProbabilities{1, 0, 0}, SceneProbabilities{0, 0, 1}}) {
    EXPECT_TRUE(f.observe(p).accepted());
    EXPECT_EQ(f.sigma(), 3.0);
    expect_relative(f.geodetic(llh), eq21(3.0, llh(0), llh(2)), 1e-12);
  }
  EXPECT_EQ(f.observe({kNaN, 0.5, 0.5}).problem, Problem::measurement_noise_non_finite);
  EXPECT_EQ(f.observe({0.9, 0.2, -0.1}).problem, Problem::measurement_out_of_domain);
  EXPECT_EQ(f.sigma(), 3.0);
}

TEST(SceneNoise, RFromThePolicyIsInTheUnitsOfTheGeodeticUpdate) {
  // Prior position variance 9 m^2 on each NED axis, nothing else correlated, lever arm zero:
  // the posterior variance in metres is 9 s^2 / (9 + s^2) per axis, s from eq. 20.
  using Nav = models::InsNavModel<>;
  const Nav model;
  SceneAdaptiveGnssNoise n;
  ASSERT_TRUE(n.observe({0.8, 0.19, 0.01}).accepted());
  eskf::Belief<Nav> b;
  b.nominal.get<"p">() = Eigen::Vector3d(24.85 * kDeg, 102.7 * kDeg, 1890.0);
  b.nominal.get<"theta">() = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  b.cov = Vector<15>::Constant(1e-4).asDiagonal();
  b.cov.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() * 9.0;
  models::GnssGeodeticPosition<models::NavState> gnss;
  gnss.R = n.geodetic(b.nominal.get<"p">());
  // A fix 3 m north of the estimate: the correction is 3 * 9 / (9 + s^2) m north.
  const Vector<3> z = earth::GeodeticRetraction::inject(b.nominal.get<"p">(), Eigen::Vector3d(3.0, 0.0, 0.0));
  const Eigen::Vector3d before = b.nominal.get<"p">();
  ASSERT_TRUE(eskf::update(model, gnss, b, z).accepted());
  const double s2 = 4.5 * 4.5;
  const double gain = 9.0 / (9.0 + s2);
  // The reset after the correction rescales the error to the radii at the new latitude
  // (a relative 1e-7 here): G from the block's reset Jacobian, applied to the formula.
  const Eigen::Vector3d dx(3.0 * gain, 0.0, 0.0);
  const Eigen::Matrix3d G = earth::GeodeticRetraction::reset_jacobian(before, dx);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(b.cov(i, i), G(i, i) * G(i, i) * 9.0 * s2 / (9.0 + s2), 1e-9) << i;
  const Eigen::Vector3d moved = earth::GeodeticRetraction::difference(b.nominal.get<"p">(), before);
  EXPECT_NEAR(moved(0), 3.0 * gain, 1e-9);
  EXPECT_NEAR(moved(1), 0.0, 1e-9);
}

}  // namespace

// The one dynamic alignment (models/alignment.hpp) against hand computations (the receiver's
// velocity, the straight-track test), and on the three platforms' motions, simulated with the
// GNSS/INS pipeline's options (pipelines/gins: settings_for each platform): a car at 5-20 m/s,
// a pedestrian at 1.2 m/s with turns every few metres (1 Hz and 4 Hz fixes, with and without
// the receiver's velocity) and a ground robot at 0.3 m/s. Each must align within seconds of
// moving off with its heading inside 3 of its own sigmas.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "ctxfuse/models/alignment.hpp"
#include "ctxfuse/pipelines/gins/forward.hpp"
#include "gins/states.hpp"

namespace {
using namespace ctxfuse;
namespace gins = ctxfuse::pipelines::gins;
using ctxfuse::test::kDeg;

TEST(DynamicAligner, ReceiverVelocityGivesTheHeadingWithItsCrossTrackSigma) {
  models::AlignmentOptions o;
  o.max_heading_sigma = 2.0 * kDeg;
  models::DynamicAligner aligner(o);
  models::PlanarFix f;
  f.t = 1.0;
  f.p = {3.0, 4.0};
  f.cov = Eigen::Matrix2d::Identity() * 1e-4;
  f.has_velocity = true;
  // 1 m/s along x, sigma 0.05 m/s per axis: heading sigma 0.05 rad (2.9 deg) > 2 deg.
  f.v = {1.0, 0.0};
  f.v_cov = Eigen::Matrix2d::Identity() * 0.0025;
  EXPECT_FALSE(aligner.add(f).has_value());
  // 2 m/s at 30 deg with a cross-track variance of 0.03^2 and along-track 0.3^2: only the
  // cross-track part counts, sigma 0.015 rad.
  const double a = 30.0 * kDeg;
  const Eigen::Vector2d along(std::cos(a), std::sin(a)), across(-std::sin(a), std::cos(a));
  f.t = 2.0;
  f.v = 2.0 * along;
  f.v_cov = 0.09 * along * along.transpose() + 0.0009 * across * across.transpose();
  const auto al = aligner.add(f);
  ASSERT_TRUE(al.has_value());
  EXPECT_EQ(al->source, models::HeadingSource::receiver_velocity);
  EXPECT_NEAR(al->heading, a, 1e-12);
  EXPECT_NEAR(std::sqrt(al->heading_var), 0.03 / 2.0, 1e-12);
  EXPECT_EQ(al->velocity, f.v);
  EXPECT_EQ(al->position, f.p);
}

TEST(DynamicAligner, OptionsOutOfRangeAreNamedAndRefusedAtConstruction) {
  models::AlignmentOptions o;
  ASSERT_TRUE(o.check().ok());
  o.max_span_s = std::nan("");
  const SettingCheck c = o.check();
  EXPECT_EQ(c.problem, Problem::invalid_setting);
  EXPECT_NE(c.what.find("max_span_s"), std::string_view::npos) << c.what;
  EXPECT_THROW(models::DynamicAligner{o}, std::invalid_argument);
  o = {};
  o.heading_sigma_floor = -0.1;
  EXPECT_NE(o.check().what.find("floors"), std::string_view::npos);
  EXPECT_THROW(models::DynamicAligner{o}, std::invalid_argument);
}

TEST(DynamicAligner, AChordAcrossATurnIsNoHeadingTheStraightPartIs) {
  models::AlignmentOptions o;
  o.min_distance_m = 1.0;
  o.max_heading_sigma = 5.0 * kDeg;
  o.straight_track = true;
  const Eigen::Matrix2d cov = Eigen::Matrix2d::Identity() * 0.0025;  // 5 cm
  // 4 m east, then a 90 deg left turn and 3 m north, one fix a metre.
  std::vector<Eigen::Vector2d> path;
  for (int k = 0; k <= 4; ++k) path.emplace_back(k, 0.0);
  for (int k = 1; k <= 3; ++k) path.emplace_back(4.0, k);
  models::DynamicAligner aligner(o);
  std::optional<models::PlanarAlignment> al;
  for (std::size_t k = 0; k < path.size() && !al; ++k) al = aligner.add(static_cast<double>(k), path[k], cov);
  // The first qualifying baseline is (0,0)-(2,0) at t = 2 s (2 m: sigma 0.0707/2 = 2.0 deg).
  ASSERT_TRUE(al.has_value());
  EXPECT_EQ(al->t, 2.0);
  EXPECT_NEAR(al->heading, 0.0, 1e-12);
  // After the turn: without the test the longest baseline is the chord from (0,0), 37 deg off
  // the new heading; with it, the longest straight one, from the corner.
  models::AlignmentOptions loose = o;
  loose.straight_track = false;
  models::DynamicAligner chord(loose), straight(o);
  for (std::size_t k = 0; k + 1 < path.size(); ++k) {
    chord.add(static_cast<double>(k), path[k], cov);
    straight.add(static_cast<double>(k), path[k], cov);
  }
  const auto c = chord.add(7.0, path.back(), cov);
  const auto s = straight.add(7.0, path.back(), cov);
  ASSERT_TRUE(c.has_value());
  ASSERT_TRUE(s.has_value());
  EXPECT_NEAR(c->heading, std::atan2(3.0, 4.0), 1e-12);
  EXPECT_NEAR(s->heading, std::numbers::pi / 2.0, 1e-12);
  EXPECT_NEAR(s->baseline_m, 3.0, 1e-12);
}

// A platform's motion: at rest for rest_s, then along a route of straight legs (length leg_m,
// then a 90 deg turn of radius turn_r_m) at `speed`, reached with `accel`.
struct Motion {
  double rest_s, speed, accel, leg_m, turn_r_m;
};

struct PlanarState {
  Eigen::Vector2d p, v;
  double heading;
};

// Integrates the motion at 1 kHz and samples it at the fix times.
std::vector<std::pair<double, PlanarState>> simulate(const Motion& m, double fix_hz, double duration_s) {
  std::vector<std::pair<double, PlanarState>> out;
  const double dt = 1e-3;
  PlanarState x{Eigen::Vector2d(10.0, -5.0), Eigen::Vector2d::Zero(), 20.0 * kDeg};
  double speed = 0.0, along_leg = 0.0, turned = 0.0;
  bool turning = false;
  const auto steps = static_cast<long>(std::llround(duration_s / dt));
  const auto every = static_cast<long>(std::llround(1.0 / (fix_hz * dt)));
  for (long i = 0; i <= steps; ++i) {
    const double t = static_cast<double>(i) * dt;
    if (i % every == 0) out.emplace_back(t, x);
    if (t < m.rest_s) continue;
    speed = std::min(m.speed, speed + m.accel * dt);
    double rate = 0.0;
    if (turning) {
      rate = speed / m.turn_r_m;
      turned += rate * dt;
      if (turned >= std::numbers::pi / 2.0) turning = false, turned = 0.0, along_leg = 0.0;
    } else {
      along_leg += speed * dt;
      if (along_leg >= m.leg_m) turning = true;
    }
    x.heading += rate * dt;
    x.v = speed * Eigen::Vector2d(std::cos(x.heading), std::sin(x.heading));
    x.p += x.v * dt;
  }
  return out;
}

struct AlignOutcome {
  std::optional<models::PlanarAlignment> al;
  double heading_true = 0.0;
};

// Fixes with white noise (position sigma_p per axis, velocity sigma_v), reported with those
// sigmas and floored as the GNSS/INS pass floors them (RTK fixed: 5 cm, velocity 5 cm/s).
AlignOutcome align(const Motion& m, gins::Platform platform, double fix_hz, bool with_velocity, double sigma_p, unsigned seed) {
  const gins::Settings s = gins::settings_for(platform);
  models::DynamicAligner aligner(gins::alignment_options(s));
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  const double sigma_v = 0.03;
  const double floor_p = std::max(sigma_p, s.gnss_position_sigma_floor_m);
  const double floor_v = std::max(sigma_v, s.gnss_velocity_sigma_floor_mps);
  AlignOutcome o;
  for (const auto& [t, x] : simulate(m, fix_hz, m.rest_s + 30.0)) {
    models::PlanarFix f;
    f.t = t;
    f.p = x.p + sigma_p * Eigen::Vector2d(n(rng), n(rng));
    f.cov = Eigen::Matrix2d::Identity() * floor_p * floor_p;
    f.has_velocity = with_velocity;
    f.v = x.v + sigma_v * Eigen::Vector2d(n(rng), n(rng));
    f.v_cov = Eigen::Matrix2d::Identity() * floor_v * floor_v;
    o.al = aligner.add(f);
    if (o.al) {
      o.heading_true = x.heading;
      break;
    }
  }
  return o;
}

void expect_aligned(const AlignOutcome& o, const Motion& m, double within_s, const char* what) {
  ASSERT_TRUE(o.al.has_value()) << what;
  EXPECT_GT(o.al->t, m.rest_s) << what << ": aligned while at rest";
  EXPECT_LE(o.al->t - m.rest_s, within_s) << what;
  const double err = std::remainder(o.al->heading - o.heading_true, 2.0 * std::numbers::pi);
  EXPECT_LT(std::abs(err), 3.0 * std::sqrt(o.al->heading_var)) << what << ": heading error " << err / kDeg << " deg";
}

TEST(PlatformAlignment, ACarAtFiveToTwentyMetresASecondAlignsWithinTwoSecondsOfMovingOff) {
  for (double v : {5.0, 10.0, 20.0})
    for (bool vel : {true, false})
      for (unsigned seed = 1; seed <= 5; ++seed) {
        const Motion car{8.0, v, 2.5, 200.0, 30.0};
        const AlignOutcome o = align(car, gins::Platform::car, 4.0, vel, 0.02, seed);
        expect_aligned(o, car, 2.0, vel ? "car, receiver velocity" : "car, positions");
        if (vel) {
          EXPECT_EQ(o.al->source, models::HeadingSource::receiver_velocity);
        }
      }
}

TEST(PlatformAlignment, APedestrianWithTightTurnsAlignsWithinSecondsAtOneAndFourHertz) {
  // 1.2 m/s, a turn of 1 m radius every 4 m.
  const Motion walk{12.0, 1.2, 1.0, 4.0, 1.0};
  for (double hz : {1.0, 4.0})
    for (bool vel : {true, false})
      for (unsigned seed = 1; seed <= 5; ++seed) {
        const AlignOutcome o = align(walk, gins::Platform::pedestrian, hz, vel, 0.02, seed);
        // 5 deg needs 0.8 m with RTK fixes, i.e. the first metre (the 1 m minimum) and the fix after it.
        expect_aligned(o, walk, hz == 1.0 ? 3.5 : 2.5, vel ? "walk, receiver velocity" : "walk, positions");
      }
  // Float fixes (25 cm floor): 5 deg needs a 4 m straight baseline, one whole leg.
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const AlignOutcome o = align(walk, gins::Platform::pedestrian, 4.0, false, 0.2, seed);
    ASSERT_TRUE(o.al.has_value());
    const double err = std::remainder(o.al->heading - o.heading_true, 2.0 * std::numbers::pi);
    EXPECT_LT(std::abs(err), 3.0 * std::sqrt(o.al->heading_var)) << "float, seed " << seed;
  }
}

TEST(PlatformAlignment, ARobotAtThirtyCentimetresASecondAlignsWithinTenSeconds) {
  const Motion robot{10.0, 0.3, 0.5, 6.0, 0.5};
  for (bool vel : {true, false})
    for (unsigned seed = 1; seed <= 5; ++seed) {
      const AlignOutcome o = align(robot, gins::Platform::robot, 4.0, vel, 0.02, seed);
      // 3 deg with 5 cm fixes: a 1.35 m baseline, 4.5 s at 0.3 m/s (the receiver's velocity,
      // 0.05 m/s at 0.3 m/s, is 9.5 deg: never enough).
      expect_aligned(o, robot, 10.0, "robot");
      EXPECT_EQ(o.al->source, models::HeadingSource::baseline);
    }
}

}  // namespace

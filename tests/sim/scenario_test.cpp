// Named scenarios (sim/scenarios.hpp) and the UWB options behind the "paper" one: anchors only
// inside the garage, and garage walls opaque to UWB so that ranges between inside and outside
// travel round a door jamb. References are hand-computed geometry, written out here.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "ctxfuse/sim/drive.hpp"
#include "ctxfuse/sim/scenarios.hpp"

namespace sim = ctxfuse::sim;

namespace {

const sim::Drive& paper_drive() {
  static const sim::Drive d = [] {
    sim::DriveConfig c = sim::paper_scenario();
    c.seed = 1;
    return sim::simulate_drive(c);
  }();
  return d;
}

Eigen::Vector3d tag_at(const sim::Drive& d, double t) {
  const auto k = static_cast<std::size_t>(std::lround(t * d.config.imu.rate_hz));
  const auto& p = d.truth[std::min(k, d.truth.size() - 1)].position;
  return {p.x(), p.y(), d.config.uwb.tag_height_m};
}

// The site's doorway: x = 0, y in [-5, 5] (route.hpp: door_half = 5).
constexpr double kDoorHalf = 5.0;

}  // namespace

TEST(SimScenario, NamesSelectTheFactoriesAndUnknownNamesAreRejected) {
  const sim::DriveConfig def = sim::scenario_config("default");
  EXPECT_TRUE(def.route.approach_uwb_anchors);
  EXPECT_FALSE(def.uwb.garage_walls_opaque);
  const sim::DriveConfig paper = sim::scenario_config("paper");
  EXPECT_FALSE(paper.route.approach_uwb_anchors);
  EXPECT_TRUE(paper.uwb.garage_walls_opaque);
  try {
    (void)sim::scenario_config("papr");
    FAIL() << "an unknown scenario must throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("papr"), std::string::npos) << e.what();
  }
}

TEST(SimScenario, DoorwayPathIsTheDiffractedPathRoundTheNearerJamb) {
  const sim::Route route = sim::make_route(sim::RouteConfig{});
  const sim::World& w = route.world;
  // Garage anchor 0 sits 3 m inside the west wall, 3 m from the north wall (garage half-width
  // 24 m): (3, 21, 2.8). Tag 20 m out in the approach on its axis at 1 m height.
  const Eigen::Vector3d anchor(3.0, 21.0, 2.8), tag(-20.0, 0.0, 1.0);
  // By hand: round the north jamb (0, 5): horizontal legs sqrt(3^2 + 16^2) + sqrt(20^2 + 5^2)
  // = 16.27882 + 20.61553 = 36.89435, with the 1.8 m height difference sqrt(36.89435^2 +
  // 1.8^2) = 36.93823 m; round the south jamb it is 46.82 m; the straight line is
  // sqrt(23^2 + 21^2 + 1.8^2) = 31.19679 m, so the range is 5.74 m too long.
  const auto path = sim::detail::doorway_path_length(w, anchor, tag);
  ASSERT_TRUE(path.has_value());
  EXPECT_NEAR(*path, 36.93823, 1e-4);
  EXPECT_NEAR(*path - (anchor - tag).norm(), 36.93823 - 31.19679, 1e-4);
  // Symmetric in its ends.
  EXPECT_NEAR(*sim::detail::doorway_path_length(w, tag, anchor), *path, 1e-12);
  // Through the opening (the east anchor on the axis) or on the same side: no bent path.
  EXPECT_FALSE(sim::detail::doorway_path_length(w, Eigen::Vector3d(30.0, 0.0, 2.8), tag).has_value());
  EXPECT_FALSE(sim::detail::doorway_path_length(w, anchor, Eigen::Vector3d(20.0, 0.0, 1.0)).has_value());
  EXPECT_FALSE(sim::detail::doorway_path_length(w, Eigen::Vector3d(-30.0, 3.0, 3.0), tag).has_value());
}

TEST(SimScenario, PaperScenarioKeepsEveryAnchorInsideTheGarage) {
  const sim::Drive& d = paper_drive();
  EXPECT_EQ(d.world().anchors.size(), 5u);
  for (const auto& a : d.world().anchors)
    EXPECT_EQ(d.world().region_at(Eigen::Vector2d(a.position.head<2>())), sim::Region::indoor) << "anchor " << a.id;
  // The default keeps the two approach anchors.
  const sim::Route def = sim::make_route(sim::RouteConfig{});
  EXPECT_EQ(def.world.anchors.size(), 7u);
}

TEST(SimScenario, RangesFromOutsideTheGarageAreBentRoundTheDoorWithGeometricBias) {
  const sim::Drive& d = paper_drive();
  const auto& c = d.config.uwb;
  int outside = 0, bent = 0;
  std::vector<double> residual, bias_near, bias_far;
  for (const auto& r : d.uwb) {
    const Eigen::Vector3d tag = tag_at(d, r.t);
    if (d.world().region_at(Eigen::Vector2d(tag.head<2>())) == sim::Region::indoor) continue;
    ++outside;
    // Independent reference: does the straight line cross x = 0 inside the opening?
    const Eigen::Vector3d& a = r.anchor_position;
    const double s = (0.0 - tag.x()) / (a.x() - tag.x());
    const double y_at_wall = tag.y() + s * (a.y() - tag.y());
    if (std::abs(y_at_wall) < kDoorHalf) continue;  // through the opening: not bent
    ++bent;
    double path = 1e9;
    for (double jy : {kDoorHalf, -kDoorHalf}) {
      const double h = std::hypot(a.x(), a.y() - jy) + std::hypot(tag.x(), tag.y() - jy);
      path = std::min(path, std::hypot(h, a.z() - tag.z()));
    }
    const double straight = (a - tag).norm();
    EXPECT_TRUE(r.nlos);
    EXPECT_NEAR(r.true_range_m, straight, 1e-6);
    EXPECT_NEAR(r.nlos_bias_m, path - straight, 1e-6) << "tag " << tag.transpose() << " anchor " << r.anchor_id;
    EXPECT_LE(path, c.max_range_nlos_m + 1e-9);  // the bent path, not the straight line, limits reach
    residual.push_back(r.range_m - r.true_range_m - r.nlos_bias_m);
    (tag.x() > -5.0 ? bias_near : bias_far).push_back(r.nlos_bias_m);
  }
  ASSERT_GT(bent, 30) << "the drive must produce bent ranges outside the garage (" << outside << " outside)";
  // White noise of an NLOS range: sqrt(0.10^2 + 0.30^2) = 0.316 m.
  double m = 0.0, v = 0.0;
  for (double x : residual) m += x;
  m /= static_cast<double>(residual.size());
  for (double x : residual) v += (x - m) * (x - m);
  const double sd = std::sqrt(v / static_cast<double>(residual.size() - 1));
  EXPECT_NEAR(sd, std::hypot(c.range_noise_m, c.nlos_extra_noise_m), 0.08);
  EXPECT_NEAR(m, 0.0, 4.0 * sd / std::sqrt(static_cast<double>(residual.size())));
  // The paper's "error grows as the vehicle moves outwards": further from the door, longer detour.
  ASSERT_FALSE(bias_near.empty());
  ASSERT_FALSE(bias_far.empty());
  auto avg = [](const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return s / static_cast<double>(v.size());
  };
  EXPECT_GT(avg(bias_far), avg(bias_near));
}

TEST(SimScenario, UwbNeverReachesTheStreetInEitherScenario) {
  // The approach is the route solver's length for the 19.1 % transition share (well over 100 m),
  // so no anchor is within a DW1000's range of the street.
  for (const char* name : {"default", "paper"}) {
    sim::DriveConfig c = sim::scenario_config(name);
    c.seed = 2;
    const sim::Drive d = sim::simulate_drive(c);
    int street = 0;
    for (const auto& r : d.uwb)
      street += d.world().region_at(Eigen::Vector2d(tag_at(d, r.t).head<2>())) == sim::Region::outdoor;
    EXPECT_EQ(street, 0) << name;
  }
}

TEST(SimScenario, IndoorFixesChangeNothingButTheIndoorEpochs) {
  // The option draws no random numbers: everything outside the garage, and every other
  // sensor, is bit-identical to the drive without it; indoors every epoch gets a fix whose
  // error is the option's std times one unit process, so it scales exactly with the std.
  sim::DriveConfig c;
  c.seed = 4;
  const sim::Drive plain = sim::simulate_drive(c);
  c.gnss.indoor_fix_error_m = 2.0;
  c.gnss.indoor_fix_reported_ratio = 0.25;
  const sim::Drive two = sim::simulate_drive(c);
  c.gnss.indoor_fix_error_m = 6.0;
  const sim::Drive six = sim::simulate_drive(c);

  ASSERT_EQ(plain.gnss.size(), two.gnss.size());
  ASSERT_EQ(plain.uwb.size(), two.uwb.size());
  ASSERT_EQ(plain.imu.size(), two.imu.size());
  for (std::size_t i = 0; i < plain.uwb.size(); ++i) EXPECT_EQ(plain.uwb[i].range_m, two.uwb[i].range_m);
  for (std::size_t i = 0; i < plain.imu.size(); i += 97) EXPECT_EQ(plain.imu[i].accel, two.imu[i].accel);
  std::size_t indoor = 0;
  for (std::size_t i = 0; i < plain.gnss.size(); ++i) {
    const auto &a = plain.gnss[i], &b = two.gnss[i], &e6 = six.gnss[i];
    EXPECT_EQ(a.num_sats, b.num_sats);
    EXPECT_EQ(a.mean_cn0_dbhz, b.mean_cn0_dbhz);  // recognition features untouched
    if (a.region != sim::Region::indoor) {
      EXPECT_EQ(a.has_fix, b.has_fix);
      EXPECT_EQ(a.position, b.position);
      EXPECT_EQ(a.std_horizontal_m, b.std_horizontal_m);
      continue;
    }
    ++indoor;
    EXPECT_FALSE(a.has_fix);
    ASSERT_TRUE(b.has_fix) << "t = " << b.t;
    ASSERT_TRUE(e6.has_fix);
    EXPECT_DOUBLE_EQ(b.std_horizontal_m, 0.5);  // 0.25 x 2 m
    EXPECT_DOUBLE_EQ(e6.std_horizontal_m, 1.5);
    const auto k = static_cast<std::size_t>(std::lround(b.t * two.config.imu.rate_hz));
    const Eigen::Vector3d truth = two.truth[std::min(k, two.truth.size() - 1)].position;
    EXPECT_NEAR((b.position - truth - b.error).norm(), 0.0, 1e-9);
    for (int ax = 0; ax < 3; ++ax) EXPECT_NEAR(e6.error[ax], 3.0 * b.error[ax], 1e-12);
  }
  EXPECT_GT(indoor, 100u);
}

TEST(SimScenario, IndoorFixOptionsAreChecked) {
  sim::DriveConfig c;
  c.gnss.indoor_fix_error_m = -1.0;
  EXPECT_THROW((void)sim::simulate_drive(c), std::invalid_argument);
  c.gnss.indoor_fix_error_m = 1.0;
  c.gnss.indoor_fix_reported_ratio = 0.0;
  EXPECT_THROW((void)sim::simulate_drive(c), std::invalid_argument);
  c.gnss.indoor_fix_reported_ratio = std::nan("");
  EXPECT_THROW((void)sim::simulate_drive(c), std::invalid_argument);
}

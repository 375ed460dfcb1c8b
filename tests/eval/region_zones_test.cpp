// The region study's zones and counts (studies/region_zones.hpp) on a simulated drive: the
// zones partition every measurement, the drive passes them in order, and the gate counter
// books each offered update once, in its zone and taker, with the NLOS truth of its range.
#include <gtest/gtest.h>

#include <ctxfuse/sim/drive.hpp>
#include <ctxfuse/sim/scenarios.hpp>
#include <ctxfuse/studies/region_zones.hpp>

#include <cmath>
#include <cstdlib>

namespace {

using namespace ctxfuse;
using namespace ctxfuse::studies::region_zones;
namespace ri = ctxfuse::pipelines::region_imm;

const sim::Drive& drive() {
  static const sim::Drive d = [] {
    sim::DriveConfig c = sim::scenario_config("default");
    c.seed = 3;
    return sim::simulate_drive(c);
  }();
  return d;
}

TEST(RegionZones, ThePicturePartitionsEveryMeasurement) {
  const Zoning zones(drive());
  const Picture p = sensor_picture(drive(), zones);
  int gnss = 0, fixes = 0, ranges = 0, nlos = 0, uwb_epochs = 0;
  for (const auto& z : p) {
    gnss += z.gnss_epochs, fixes += z.fixes, ranges += z.ranges, nlos += z.nlos, uwb_epochs += z.uwb_epochs;
    EXPECT_LE(z.fixes, z.gnss_epochs);
    EXPECT_LE(z.nlos, z.ranges);
  }
  int true_fixes = 0, true_nlos = 0;
  for (const auto& e : drive().gnss) true_fixes += e.has_fix;
  for (const auto& r : drive().uwb) true_nlos += r.nlos;
  EXPECT_EQ(gnss, static_cast<int>(drive().gnss.size()));
  EXPECT_EQ(fixes, true_fixes);
  EXPECT_EQ(ranges, static_cast<int>(drive().uwb.size()));
  EXPECT_EQ(nlos, true_nlos);
  const double rate = drive().config.uwb.rate_hz;
  EXPECT_EQ(uwb_epochs, static_cast<int>(std::floor(drive().duration() * rate + 1e-9)) + 1);
  // The default drive goes from the street into the garage: every zone is visited.
  for (int k = 0; k < kZones; ++k) EXPECT_GT(p[static_cast<std::size_t>(k)].gnss_epochs, 0) << kZoneName[static_cast<std::size_t>(k)];
}

TEST(RegionZones, TheDrivePassesTheZonesInOrder) {
  // Zones are numbered along the approach, so one GNSS epoch to the next moves at most one zone.
  const Zoning zones(drive());
  int previous = zones.at_time(drive().gnss.front().t), changes = 0;
  for (const auto& e : drive().gnss) {
    const int z = zones.at_time(e.t);
    EXPECT_LE(std::abs(z - previous), 1) << "t = " << e.t;
    changes += z != previous;
    previous = z;
  }
  EXPECT_GE(changes, kZones - 1);
}

TEST(RegionZones, TheGateCounterBooksEachOfferOnce) {
  const Zoning zones(drive());
  const NlosTruth nlos = nlos_truth(drive());
  GateTable table{};
  GateCounter count{zones, nlos, table};
  const double t_fix = drive().gnss[drive().gnss.size() / 2].t;
  const auto zone_fix = static_cast<std::size_t>(zones.at_time(t_fix));
  ri::UpdateEvent fix;
  fix.source = ri::Source::gnss;
  fix.t = t_fix;
  fix.takers = 4;
  fix.offered = {true, true, false, true};
  fix.gated = {false, true, true, true};  // the third taker was not offered: its verdict is not counted
  count(fix);
  EXPECT_EQ(table[0][0][zone_fix].offered, 1);
  EXPECT_EQ(table[0][0][zone_fix].gated, 0);
  EXPECT_EQ(table[0][1][zone_fix].gated, 1);
  EXPECT_EQ(table[0][2][zone_fix].offered, 0);
  EXPECT_EQ(table[0][3][zone_fix].gated, 1);

  const auto* blocked = &drive().uwb.front();
  for (const auto& r : drive().uwb)
    if (r.nlos) {
      blocked = &r;
      break;
    }
  ASSERT_TRUE(blocked->nlos);
  const auto zone_range = static_cast<std::size_t>(zones.at_time(blocked->t));
  ri::UpdateEvent range;
  range.source = ri::Source::uwb;
  range.t = blocked->t;
  range.anchor_id = blocked->anchor_id;
  range.takers = 1;
  range.offered = {true, false, false, false};
  range.gated = {false, false, false, false};
  count(range);
  range.gated[0] = true;
  count(range);
  EXPECT_EQ(table[1][0][zone_range].offered, 2);
  EXPECT_EQ(table[1][0][zone_range].gated, 1);
  EXPECT_EQ(table[1][0][zone_range].nlos_offered, 2);
  EXPECT_EQ(table[1][0][zone_range].nlos_accepted, 1);
  // An anchor with no range at that time carries no NLOS truth.
  range.anchor_id = -7;
  count(range);
  EXPECT_EQ(table[1][0][zone_range].offered, 3);
  EXPECT_EQ(table[1][0][zone_range].nlos_offered, 2);
  int booked = 0;
  for (const auto& src : table)
    for (const auto& taker : src)
      for (const auto& z : taker) booked += z.offered;
  EXPECT_EQ(booked, 3 + 3);
}

}  // namespace

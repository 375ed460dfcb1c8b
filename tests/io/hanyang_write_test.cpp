// io::write_hanyang_case against the reader: ranges and reference written in the dataset's
// layout read back the same (stamps to the ns, numbers to the last digit, unknown powers as
// unknown); the header line is the real files' (real data; that check skipped without it); bad
// input is refused before any file is written.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "ctxfuse/io/hanyang_uwb.hpp"
#include "support/data_dir.hpp"

namespace fs = std::filesystem;
using ctxfuse::io::HanyangReferencePose;
using ctxfuse::messages::UwbRange;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("ctxfuse_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  return p;
}

UwbRange range(double t, int id, Eigen::Vector3d a, double r, double rssi, double fp) {
  UwbRange u;
  u.t = t;
  u.anchor_id = id;
  u.anchor_position = a;
  u.range_m = r;
  u.rssi_dbm = rssi;
  u.rssi_first_path_dbm = fp;
  return u;
}

std::string first_line(const fs::path& p) {
  std::ifstream is(p);
  std::string line;
  std::getline(is, line);
  return line;
}

}  // namespace

TEST(HanyangWrite, RoundTrip) {
  const fs::path dir = scratch("hanyang_write");
  const double nan = ctxfuse::messages::kUnknown;
  // Anchor 12 before anchor 3 at one stamp: the reader orders by time, then id.
  const std::vector<UwbRange> in{range(1732085150.571773934, 3, {2.5775, -0.87, 1.97}, 6.210032333333333, -79.89, -80.65),
                                 range(1732085150.6, 12, {-1.0 / 3.0, 0.1, 0.5}, 0.0, nan, -81.5),
                                 range(1732085150.6, 3, {2.5775, -0.87, 1.97}, 123.456789012345, -79.0, nan),
                                 range(1732085150.7, 12, {-1.0 / 3.0, 0.1, 0.5}, 7.25, -80.0, -81.0)};
  std::vector<HanyangReferencePose> ref(3);
  for (int i = 0; i < 3; ++i) {
    ref[static_cast<std::size_t>(i)].t = 1732085150.5 + 0.125 * i;
    ref[static_cast<std::size_t>(i)].position = {-2.5775 + i / 3.0, -4.27, 0.012 * i};
    ref[static_cast<std::size_t>(i)].heading_deg = 370.5 * i;
  }
  ctxfuse::io::write_hanyang_case(dir, in, ref);
  const auto c = ctxfuse::io::read_hanyang_uwb(dir);
  ASSERT_EQ(c.ranges.size(), 4u);
  EXPECT_EQ(c.ranges_per_anchor.at(3), 2u);
  EXPECT_EQ(c.ranges_per_anchor.at(12), 2u);
  EXPECT_EQ(c.non_finite_rssi, 2u);
  EXPECT_EQ(c.ranges[0].t_ns, std::llround(in[0].t * 1e9));  // the stamp, rounded to the ns
  EXPECT_EQ(c.ranges[1].range.anchor_id, 3);  // same stamp as anchor 12's: lower id first
  EXPECT_EQ(c.ranges[2].range.anchor_id, 12);
  const std::size_t order[] = {0, 2, 1, 3};
  for (std::size_t k = 0; k < 4; ++k) {
    const UwbRange& a = in[order[k]];
    const UwbRange& b = c.ranges[k].range;
    EXPECT_NEAR(b.t, a.t, 2.5e-7);  // a double at 1.7e9 s: 0.24 us steps
    EXPECT_EQ(b.anchor_id, a.anchor_id);
    EXPECT_EQ(b.anchor_position, a.anchor_position);
    EXPECT_EQ(b.range_m, a.range_m);
    EXPECT_EQ(std::isnan(b.rssi_dbm), std::isnan(a.rssi_dbm));
    EXPECT_EQ(std::isnan(b.rssi_first_path_dbm), std::isnan(a.rssi_first_path_dbm));
    if (!std::isnan(a.rssi_dbm)) {
      EXPECT_EQ(b.rssi_dbm, a.rssi_dbm);
    }
    if (!std::isnan(a.rssi_first_path_dbm)) {
      EXPECT_EQ(b.rssi_first_path_dbm, a.rssi_first_path_dbm);
    }
  }
  const auto back = ctxfuse::io::read_hanyang_reference(dir);
  ASSERT_EQ(back.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR(back[i].t, ref[i].t, 2.5e-7);
    EXPECT_EQ(back[i].position, ref[i].position);
    EXPECT_EQ(back[i].heading_deg, ref[i].heading_deg);
  }
  fs::remove_all(dir);
}

TEST(HanyangWrite, HeadersAreTheRealFiles) {
  CTXFUSE_REQUIRE_DATA(real, "uwb-outdoor-hanyang/Dynamic_measurements/NLOS/Trajectory_A/Case_1");
  const fs::path dir = scratch("hanyang_write_header");
  const std::vector<UwbRange> in{range(1.0, 3, {1, 2, 3}, 4.0, -80, -81)};
  std::vector<HanyangReferencePose> ref(2);
  ref[1].t = 1.0;
  ctxfuse::io::write_hanyang_case(dir, in, ref);
  EXPECT_EQ(first_line(dir / "A3.csv"), first_line(real / "A3.csv"));
  EXPECT_EQ(first_line(dir / "trajectory.csv"), first_line(real / "trajectory.csv"));
  fs::remove_all(dir);
}

TEST(HanyangWrite, BadInputWritesNothing) {
  const fs::path dir = scratch("hanyang_write_bad");
  const Eigen::Vector3d a(1, 2, 3);
  const std::vector<std::vector<UwbRange>> bad{
      {range(1.0, 3, a, -0.5, -80, -81)},                                  // negative range
      {range(std::nan(""), 3, a, 1.0, -80, -81)},                          // no time
      {range(1.0, 3, a, 1.0, -80, -81), range(1.0, 3, a, 2.0, -80, -81)},  // one anchor, one stamp twice
      {range(1.0, 3, a, 1.0, -80, -81), range(2.0, 3, {1, 2, 4}, 2.0, -80, -81)},  // the anchor moves
      {range(1.0, -1, a, 1.0, -80, -81)}};                                 // no such id
  for (const auto& b : bad) {
    EXPECT_THROW(ctxfuse::io::write_hanyang_case(dir, b), std::invalid_argument);
    EXPECT_FALSE(fs::exists(dir));
  }
  std::vector<HanyangReferencePose> ref(2);  // two samples at t = 0
  EXPECT_THROW(ctxfuse::io::write_hanyang_case(dir, std::vector<UwbRange>{range(1.0, 3, a, 1.0, -80, -81)}, ref), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir));
}

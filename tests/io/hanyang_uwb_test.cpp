// Hanyang dynamic-case reader on a case folder written here: the merge of per-anchor files,
// columns found by name, -inf power kept as NaN, the reference trajectory, and the errors.
#include <gtest/gtest.h>

#include <ctxfuse/io/hanyang_uwb.hpp>

#include <cmath>
#include <string>

#include "temp_files.hpp"

namespace {

using namespace ctxfuse::io;
using namespace ctxfuse::messages;
using Hanyang = ctxfuse::test::TempFiles;

const std::string kHeader = "%time,field.stamp,field.id,field.x,field.y,field.z,field.distanceFromTag,field.rssi,field.rssi_fp\n";

std::string range_row(const std::string& t, int id, const std::string& distance = "7.5", const std::string& rssi = "-79.71") {
  return t + ",1," + std::to_string(id) + ",2.5775,0.87,1.97," + distance + "," + rssi + ",-80.75\n";
}

const std::string kReference =
    "timestamp,x,y,z,heading_degrees\n"
    "1.7345014855003267e+18,-2.5775,-4.25,0.0,0.0\n"
    "1.7345014856253268e+18,-2.577500424675722,-4.249603603939604,0.011,370.5\n";

class HanyangCase : public Hanyang {
 protected:
  void SetUp() override {
    Hanyang::SetUp();
    write("A3.csv", kHeader + range_row("1734501485317590607", 3) + range_row("1734501485417273454", 3, "7.25", "-inf"));
    // Another column order and plain names: found by name all the same.
    write("A5.csv",
          "rssi_fp,rssi,distanceFromTag,z,y,x,id,time\n"
          "-90.7,-79.0,29.95,1.39,-0.13,-0.37,5,1734501485367590607\n"
          "-90.5,-78.5,29.5,1.39,-0.13,-0.37,5,1734501485417273454\n");
    write("trajectory.csv", kReference);
    write("LS.csv", "timestamp,x,y,z\n1,2,3,4\n");  // the authors' results: not an anchor file
  }
};

TEST_F(HanyangCase, MergesAnchorsInTimeOrder) {
  const auto c = read_hanyang_uwb(dir_);
  ASSERT_EQ(c.ranges.size(), 4u);
  EXPECT_EQ(c.files.size(), 2u);
  EXPECT_EQ(c.ranges_per_anchor.at(3), 2u);
  EXPECT_EQ(c.ranges_per_anchor.at(5), 2u);
  EXPECT_EQ(c.non_finite_rssi, 1u);
  EXPECT_EQ(c.ranges[0].t_ns, 1734501485317590607);
  EXPECT_EQ(c.ranges[1].t_ns, 1734501485367590607);
  EXPECT_EQ(c.ranges[2].t_ns, 1734501485417273454);
  EXPECT_EQ(c.ranges[2].range.anchor_id, 3);  // same stamp: anchor id breaks the tie
  EXPECT_EQ(c.ranges[3].range.anchor_id, 5);
  EXPECT_NEAR(c.ranges[0].range.t, 1734501485.317590607, 5e-7);
  EXPECT_NEAR(c.ranges[1].range.t - c.ranges[0].range.t, 0.05, 1e-6);

  const UwbRange& a5 = c.ranges[1].range;
  EXPECT_EQ(a5.anchor_id, 5);
  EXPECT_EQ(a5.anchor_position, Eigen::Vector3d(-0.37, -0.13, 1.39));
  EXPECT_EQ(a5.range_m, 29.95);
  EXPECT_EQ(a5.rssi_dbm, -79.0);
  EXPECT_EQ(a5.rssi_first_path_dbm, -90.7);

  const UwbRange& lost = c.ranges[2].range;  // -inf rssi: range kept, power unknown
  EXPECT_EQ(lost.range_m, 7.25);
  EXPECT_TRUE(std::isnan(lost.rssi_dbm));
  EXPECT_EQ(lost.rssi_first_path_dbm, -80.75);

  const auto plain = c.uwb_ranges();
  ASSERT_EQ(plain.size(), 4u);
  EXPECT_EQ(plain[1].range_m, 29.95);
}

TEST_F(HanyangCase, ReadsTheReferenceApart) {
  const auto ref = read_hanyang_reference(dir_);
  ASSERT_EQ(ref.size(), 2u);
  EXPECT_NEAR(ref[0].t, 1734501485.5003267, 1e-6);
  EXPECT_NEAR(ref[1].t - ref[0].t, 0.125, 1e-6);
  EXPECT_EQ(ref[1].position, Eigen::Vector3d(-2.577500424675722, -4.249603603939604, 0.011));
  EXPECT_EQ(ref[1].heading_deg, 370.5);
}

TEST_F(HanyangCase, MalformedRowsNameFileLineColumn) {
  const std::string first = kHeader + range_row("1734501485317590607", 3);  // bad row is line 3
  write("A3.csv", first + "1734501485417273454,1,3,2.5,0.8\n");
  EXPECT_PARSE_ERROR(read_hanyang_uwb(dir_), "A3.csv:3: ", "5 fields, expected 9");
  write("A3.csv", first + range_row("1734501485417273454", 3, "far"));
  EXPECT_PARSE_ERROR(read_hanyang_uwb(dir_), "A3.csv:3:7: column 'field.distanceFromTag'", "'far' is not a number");
  write("A3.csv", first + range_row("1734501485417273454", 3, "nan"));
  EXPECT_PARSE_ERROR(read_hanyang_uwb(dir_), "A3.csv:3:7: column 'field.distanceFromTag'", "'nan' is not finite");
  write("A3.csv", first + range_row("1734501485417273454", 3, "-1.5"));
  EXPECT_PARSE_ERROR(read_hanyang_uwb(dir_), "A3.csv:3:7: column 'field.distanceFromTag'", "outside [0, 1000]");
  write("A3.csv", first + range_row("1734501485317590607", 3));
  EXPECT_PARSE_ERROR(read_hanyang_uwb(dir_), "A3.csv:3:1: column '%time'", "is not after the previous row's (line 2)");
  write("A3.csv", first + range_row("1734501485417273454", 9));
  EXPECT_PARSE_ERROR(read_hanyang_uwb(dir_), "A3.csv:3:3: column 'field.id'", "anchor id 9 in the file of anchor 3");
  write("A3.csv", first + range_row("1.7e18", 3));
  EXPECT_PARSE_ERROR(read_hanyang_uwb(dir_), "A3.csv:3:1: column '%time'", "'1.7e18' has characters after the number");
  write("A3.csv", "%time,field.id,field.x,field.y,field.z,field.distanceFromTag,field.rssi\n");
  EXPECT_PARSE_ERROR(read_hanyang_uwb(dir_), "A3.csv:1: ", "header has no column 'rssi_fp'");
  write("A3.csv", "");
  EXPECT_PARSE_ERROR(read_hanyang_uwb(dir_), "A3.csv", "empty file (no header)");

  write("trajectory.csv", kReference + "1.7345014856e+18,0,0,0,0\n");
  EXPECT_PARSE_ERROR(read_hanyang_reference(dir_), "trajectory.csv:4:1: column 'timestamp'", "time is not after");
  write("trajectory.csv", kReference + "1.7345014857e+18,0,zero,0,0\n");
  EXPECT_PARSE_ERROR(read_hanyang_reference(dir_), "trajectory.csv:4:3: column 'y'", "'zero' is not a number");
}

TEST_F(Hanyang, FolderWithoutAnchorFilesIsRefused) {
  EXPECT_PARSE_ERROR(read_hanyang_uwb(dir_), dir_.string(), "no anchor range file A<id>.csv");
  EXPECT_PARSE_ERROR(read_hanyang_uwb(dir_ / "nothing"), "nothing: ", "not a folder");
  EXPECT_PARSE_ERROR(read_hanyang_reference(dir_), "trajectory.csv: ", "cannot open file");
}

}  // namespace

// The magnetometer csv of a recording (io/mag_csv.hpp): values read exactly, the simulator's
// mag.csv read as a recording's, and every rejection named with its file:line:column.
#include <gtest/gtest.h>

#include <ctxfuse/io/mag_csv.hpp>
#include <ctxfuse/sim/logs.hpp>

#include "temp_files.hpp"

namespace {
using ctxfuse::io::read_mag_csv;

class MagCsv : public ctxfuse::test::TempFiles {};

TEST_F(MagCsv, ReadsTimeAndFieldExactly) {
  const auto p = write("mag.csv", "t,mag_x,mag_y,mag_z\r\n1751990001.25,21.5,-3.125,40.75\n\n1751990001.35,+22,-3,4e1\n");
  const auto m = read_mag_csv(p);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].t, 1751990001.25);
  EXPECT_EQ(m[0].field_ut, Eigen::Vector3d(21.5, -3.125, 40.75));
  EXPECT_EQ(m[1].t, 1751990001.35);
  EXPECT_EQ(m[1].field_ut, Eigen::Vector3d(22.0, -3.0, 40.0));
}

TEST_F(MagCsv, TheSimulatorsFileReadsAsARecordings) {
  std::vector<ctxfuse::sim::MagSample> sim{{0.1, Eigen::Vector3d(20.0, 1.0 / 3.0, -45.0)}, {0.2, Eigen::Vector3d(19.5, 0.25, -44.0)}};
  std::ofstream os(dir_ / "mag.csv");
  ctxfuse::sim::Drive d;
  d.mag = sim;
  ctxfuse::sim::csv::write_log(os, d, "mag.csv");
  os.close();
  const auto m = read_mag_csv(dir_ / "mag.csv");
  ASSERT_EQ(m.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(m[k].t, sim[k].t);
    EXPECT_EQ(m[k].field_ut, sim[k].field_ut);  // shortest round-trip text: bit for bit
  }
}

TEST_F(MagCsv, RejectsWhatIsNotAMagnetometerLog) {
  EXPECT_PARSE_ERROR(read_mag_csv(write("a.csv", "")), "a.csv", "empty file");
  EXPECT_PARSE_ERROR(read_mag_csv(write("b.csv", "t,x,y,z\n1,2,3,4\n")), "b.csv:1", "expected the header 't,mag_x,mag_y,mag_z'");
  EXPECT_PARSE_ERROR(read_mag_csv(write("c.csv", "t,mag_x,mag_y,mag_z\n1,2,3\n")), "c.csv:2", "");
  EXPECT_PARSE_ERROR(read_mag_csv(write("d.csv", "t,mag_x,mag_y,mag_z\n1,2,abc,4\n")), "d.csv:2:3", "");
  EXPECT_PARSE_ERROR(read_mag_csv(write("e.csv", "t,mag_x,mag_y,mag_z\n1,2,nan,4\n")), "e.csv:2:3", "");
  EXPECT_PARSE_ERROR(read_mag_csv(write("f.csv", "t,mag_x,mag_y,mag_z\n2,20,0,40\n2,20,0,40\n")), "f.csv:3:1",
                     "time 2 is not after the previous sample's 2");
  EXPECT_PARSE_ERROR(read_mag_csv(write("g.csv", "t,mag_x,mag_y,mag_z\n2,20,0,40\n1,20,0,40\n")), "g.csv:3:1", "times must increase");
  // 30000 nT written as if it were uT: a unit error, not a field.
  EXPECT_PARSE_ERROR(read_mag_csv(write("h.csv", "t,mag_x,mag_y,mag_z\n1,30000,0,40000\n")), "h.csv:2:2",
                     "field magnitude 50000 uT is above 1000 uT");
  EXPECT_PARSE_ERROR(read_mag_csv(dir_ / "missing.csv"), "missing.csv", "cannot open file");
}

}  // namespace

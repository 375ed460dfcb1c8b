// Static UWB reader on small files written by the test: values, trailer, -inf rows, errors.
#include <gtest/gtest.h>

#include <ctxfuse/io/uwb_static.hpp>

#include <filesystem>
#include <fstream>
#include <string>

namespace {

namespace fs = std::filesystem;
using namespace ctxfuse::io;

const char* kStaticHeader =
    "timestamp,Transmission #,Reception #,maxNoise,Distance,Channel,FirstPathAmp1,FirstPathAmp2,FirstPathAmp3,"
    "Max Growth CIR,Rx Preamble Count,Standard Noise,RSSI(dBm),RSSI_fp(dBm),rtd_init,rtd_resp,resp_rx_ts,"
    "poll_tx_ts,resp_tx_ts,poll_rx_ts,anchor_id\n";

std::string row(double distance, const std::string& rssi, const std::string& fp) {
  return "1723723564.30,4840,4615,648," + std::to_string(distance) + ",5.0,6761.0,10409.0,7013.0,1842.0,230.0,36.0," +
         rssi + "," + fp + ",72130698.0,72105792.0,-711889866.0,-784020564.0,-1979639173.0,-2051744965.0,12.0\n";
}

class UwbStaticFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("ctxfuse_uwb_static_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
                                         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_ / "LOS" / "height_50.0cm");
    fs::create_directories(root_ / "NLOS" / "height_50.0cm");
    fs::create_directories(root_ / "LOS" / "height_62.5cm");
    fs::create_directories(root_ / "NLOS" / "height_62.5cm");
  }
  void TearDown() override { fs::remove_all(root_); }
  void write(const fs::path& rel, const std::string& text) { std::ofstream(root_ / rel) << text; }
  fs::path root_;
};

TEST_F(UwbStaticFiles, ReadsValuesStopsAtSummaryAndSkipsInfinitePower) {
  write("LOS/height_50.0cm/10m.csv", std::string(kStaticHeader) + row(10.25, "-79.5", "-81.0") + row(10.10, "-inf", "-80.0") +
                                         row(9.95, "-80.0", "-80.5") + "Distance Mean,10.1\nRSSI(dBm) Mean,-inf\n");
  write("NLOS/height_50.0cm/4m.csv", std::string(kStaticHeader) + row(4.4, "-78.0", "-80.0") + ",,,,,,,,,,,,, ,,,,,,,\n");
  write("LOS/height_62.5cm/6m.csv", std::string(kStaticHeader) + row(6.2, "-78.0", "-79.0"));
  write("NLOS/height_62.5cm/6m.csv", std::string(kStaticHeader));
  UwbStaticReadStats stats;
  const auto all = read_uwb_static_dataset(root_, {}, stats);
  EXPECT_EQ(stats.files, 4u);
  EXPECT_EQ(stats.skipped_non_finite_power, 1u);
  ASSERT_EQ(all.size(), 4u);  // LOS 10 m (2 rows), LOS 6 m, NLOS 4 m; NLOS 6 m empty
  EXPECT_EQ(all[0].true_distance_m, 10.0);
  EXPECT_FALSE(all[0].nlos);
  EXPECT_EQ(all[0].height_cm, 50.0);
  EXPECT_NEAR(all[0].range_residual_m(), 0.25, 1e-9);
  EXPECT_NEAR(all[0].rssi_minus_first_path_db(), 1.5, 1e-12);
  EXPECT_NEAR(all[1].range_residual_m(), -0.05, 1e-9);
  EXPECT_EQ(all[0].file_index, all[1].file_index);
  EXPECT_EQ(all[2].height_cm, 62.5);
  EXPECT_NE(all[2].file_index, all[1].file_index);
  EXPECT_TRUE(all[3].nlos);
  EXPECT_EQ(all[3].true_distance_m, 4.0);

  UwbStaticReadStats only;
  const auto some = read_uwb_static_dataset(root_, {62.5}, only);
  ASSERT_EQ(some.size(), 1u);
  EXPECT_EQ(some[0].height_cm, 62.5);
}

TEST_F(UwbStaticFiles, ErrorsNameFileLineAndColumn) {
  write("LOS/height_50.0cm/10m.csv", std::string(kStaticHeader) + row(10.2, "-79.5", "-81.0") + row(10.1, "abc", "-80.0"));
  UwbStaticReadStats stats;
  try {
    read_uwb_static_dataset(root_, {}, stats);
    FAIL() << "expected UwbDataError";
  } catch (const UwbDataError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("10m.csv:3:13: column 'RSSI(dBm)': 'abc' is not a number"), std::string::npos) << what;
    EXPECT_EQ(e.line(), 3u);
    EXPECT_EQ(e.column(), 13u);
  }
  write("LOS/height_50.0cm/10m.csv", std::string(kStaticHeader) + "1.0,2,3\n");
  try {
    read_uwb_static_dataset(root_, {}, stats);
    FAIL() << "expected UwbDataError";
  } catch (const UwbDataError& e) {
    EXPECT_NE(std::string(e.what()).find("10m.csv:2: 3 fields, expected 21 (as in the header)"), std::string::npos) << e.what();
  }
  write("LOS/height_50.0cm/10m.csv", "timestamp,Distance\n1,2\n");
  EXPECT_THROW(read_uwb_static_dataset(root_, {}, stats), UwbDataError);
  write("LOS/height_50.0cm/10m.csv", std::string(kStaticHeader) + row(-3.0, "-79.5", "-81.0"));
  EXPECT_THROW(read_uwb_static_dataset(root_, {}, stats), UwbDataError);
  fs::remove_all(root_ / "LOS" / "height_50.0cm");
  write("LOS/height_62.5cm/far.csv", std::string(kStaticHeader));
  EXPECT_THROW(read_uwb_static_dataset(root_, {}, stats), UwbDataError);  // no distance in the name
  fs::remove_all(root_ / "NLOS");
  EXPECT_THROW(read_uwb_static_dataset(root_, {}, stats), UwbDataError);
}

}  // namespace

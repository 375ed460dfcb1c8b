// The writers' files as a recording folder: `run gins` reads a folder through
// pipelines::gins::read_recording (one *.pos, one imu*.csv with its .tag), which must take
// what write_rtklib_pos and write_imu_csv_and_tag write and give back the fixes and samples.
#include <gtest/gtest.h>

#include <ctxfuse/io/imu_tag.hpp>
#include <ctxfuse/io/rtklib_pos.hpp>
#include <ctxfuse/pipelines/gins/run.hpp>

#include <cmath>
#include <cstdint>
#include <vector>

#include "temp_files.hpp"

namespace {

using namespace ctxfuse;
using RecordingWrite = test::TempFiles;

TEST_F(RecordingWrite, ReadRecordingTakesTheWritersFolder) {
  const double t0 = 1752003260.0;
  // 30 s of a 150 Hz IMU whose clock runs 50 ppm slow, and 4 Hz fixes with velocity.
  std::vector<messages::ImuSample> imu;
  std::vector<std::int64_t> ticks;
  for (int i = 0; i < 4500; ++i) {
    messages::ImuSample s;
    s.t = t0 + i / 150.0;
    s.gyro = Eigen::Vector3d(0.01, -0.02, 0.03 + 1e-5 * i);
    s.accel = Eigen::Vector3d(0.1, 0.2, -9.80665);
    imu.push_back(s);
    ticks.push_back(5000 + std::llround((s.t - t0) * (1.0 - 50e-6) * 1000.0));
  }
  std::vector<messages::GnssFix> fixes;
  for (int i = 0; i < 120; ++i) {
    messages::GnssFix f;
    f.t = t0 + 0.5 + 0.25 * i;
    f.frame = messages::PositionFrame::geodetic;
    f.position = {40.0 + 1e-7 * i, -105.0, 1600.0};
    f.cov = Eigen::Vector3d(0.0004, 0.0004, 0.0009).asDiagonal();
    f.velocity = Eigen::Vector3d(1.2, 0.0, 0.0);
    f.velocity_cov = Eigen::Matrix3d::Identity() * 0.0025;
    f.quality = messages::FixQuality::fixed;
    f.satellites_used = 14;
    fixes.push_back(f);
  }
  io::write_rtklib_pos(dir_ / "walk.pos", fixes);
  io::write_imu_csv_and_tag(dir_ / "imu.csv", imu, ticks, t0);
  const auto rec = pipelines::gins::read_recording(dir_);
  ASSERT_EQ(rec.imu.size(), imu.size());
  ASSERT_EQ(rec.fixes.size(), fixes.size());
  // Within the ms rounding of the ticks and of the tag.
  for (std::size_t i = 0; i < imu.size(); ++i) ASSERT_NEAR(rec.imu[i].t, imu[i].t, 1.5e-3) << i;
  EXPECT_TRUE(rec.imu[100].gyro.isApprox(imu[100].gyro, 1e-14));
  for (std::size_t i = 0; i < fixes.size(); ++i) {
    ASSERT_NEAR(rec.fixes[i].t, fixes[i].t, 1e-6);
    ASSERT_EQ(rec.fixes[i].position, fixes[i].position);
    ASSERT_TRUE(rec.fixes[i].velocity.has_value());
  }
}

}  // namespace

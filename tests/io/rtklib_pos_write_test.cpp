// RTKLIB .pos writer: round trips through the reader to the digits the format keeps, fixes
// through to_rtklib_pos_record, the drive's real file rewritten, and what the writer refuses.
#include <gtest/gtest.h>

#include <ctxfuse/io/rtklib_pos.hpp>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "support/data_dir.hpp"
#include "temp_files.hpp"

namespace {

using namespace ctxfuse::io;
using namespace ctxfuse::messages;
using PosWrite = ctxfuse::test::TempFiles;

double to_decimals(double v, int d) { return std::round(v * std::pow(10.0, d)) / std::pow(10.0, d); }

std::vector<RtklibPosRecord> random_records(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0), step(0.2, 1.3);
  std::vector<RtklibPosRecord> v;
  double t = 1752003258.499;  // 2025/07/08 19:34:18.499
  for (std::size_t i = 0; i < n; ++i) {
    RtklibPosRecord r;
    r.t = t;
    t += step(rng);
    r.latitude_deg = 40.0966268 + 1e-4 * u(rng);
    r.longitude_deg = -105.1474483 + 1e-4 * u(rng);
    r.height_m = 1601.474 + 3.0 * u(rng);
    r.q = std::array{1, 2, 5}[i % 3];
    r.ns = 5 + static_cast<int>(i % 20);
    r.sdn_m = 0.01 + 0.5 * std::abs(u(rng));
    r.sde_m = 0.01 + 0.5 * std::abs(u(rng));
    r.sdu_m = 0.02 + std::abs(u(rng));
    r.sdne_m = 0.1 * u(rng);
    r.sdeu_m = 0.1 * u(rng);
    r.sdun_m = 0.1 * u(rng);
    r.age_s = 1.5 * std::abs(u(rng));
    r.ratio = 999.0 * std::abs(u(rng));
    r.vn_mps = 20.0 * u(rng);
    r.ve_mps = 20.0 * u(rng);
    r.vu_mps = u(rng);
    r.sdvn_mps = r.sdve_mps = r.sdvu_mps = 0.05 + 0.01 * std::abs(u(rng));
    r.sdvne_mps = 0.01 * u(rng);
    r.sdveu_mps = 0.01 * u(rng);
    r.sdvun_mps = 0.01 * u(rng);
    v.push_back(r);
  }
  return v;
}

TEST_F(PosWrite, RecordsRoundTripToTheFormatsDigits) {
  const auto in = random_records(300, 1);
  const auto path = dir_ / "a.pos";
  write_rtklib_pos(path, in, {.velocity = true, .comments = {"program   : ctxfuse test"}});
  const auto out = read_rtklib_pos(path);
  ASSERT_EQ(out.records.size(), in.size());
  EXPECT_FALSE(out.skipped_partial_last_line);
  EXPECT_EQ(out.columns.size(), 22u);  // date and time are the two GPST fields, then 22 columns
  for (std::size_t i = 0; i < in.size(); ++i) {
    const auto &a = in[i], &b = out.records[i];
    SCOPED_TRACE(i);
    EXPECT_NEAR(b.t, to_decimals(a.t, 3), 1e-6);  // double at 1.7e9 s: 2.4e-7 s a step
    EXPECT_NEAR(b.latitude_deg, to_decimals(a.latitude_deg, 9), 1e-12);
    EXPECT_NEAR(b.longitude_deg, to_decimals(a.longitude_deg, 9), 1e-12);
    EXPECT_NEAR(b.height_m, to_decimals(a.height_m, 4), 1e-10);
    EXPECT_EQ(b.q, a.q);
    EXPECT_EQ(b.ns, a.ns);
    for (auto m : {&RtklibPosRecord::sdn_m, &RtklibPosRecord::sde_m, &RtklibPosRecord::sdu_m, &RtklibPosRecord::sdne_m,
                   &RtklibPosRecord::sdeu_m, &RtklibPosRecord::sdun_m})
      EXPECT_NEAR(b.*m, to_decimals(a.*m, 4), 1e-12);
    EXPECT_NEAR(b.age_s, to_decimals(a.age_s, 2), 1e-12);
    EXPECT_NEAR(b.ratio, to_decimals(a.ratio, 1), 1e-12);
    for (auto m : {&RtklibPosRecord::vn_mps, &RtklibPosRecord::ve_mps, &RtklibPosRecord::vu_mps, &RtklibPosRecord::sdvn_mps,
                   &RtklibPosRecord::sdve_mps, &RtklibPosRecord::sdvu_mps, &RtklibPosRecord::sdvne_mps,
                   &RtklibPosRecord::sdveu_mps, &RtklibPosRecord::sdvun_mps})
      EXPECT_NEAR(b.*m, to_decimals(a.*m, 5), 1e-12);
  }
  // Without velocity: 14 columns, velocity NaN.
  RtklibPosWriteOptions no_velocity;
  no_velocity.velocity = false;
  write_rtklib_pos(dir_ / "b.pos", in, no_velocity);
  const auto nv = read_rtklib_pos(dir_ / "b.pos");
  EXPECT_EQ(nv.columns.size(), 13u);
  EXPECT_FALSE(nv.records[0].has_velocity());
  EXPECT_NEAR(nv.records[7].sdun_m, to_decimals(in[7].sdun_m, 4), 1e-12);
}

TEST_F(PosWrite, CalendarTimeRollsOverAtTheMillisecond) {
  auto in = random_records(3, 2);
  // 2024/12/31 23:59:59.9996 rounds to 2025/01/01 00:00:00.000; a leap day before it.
  in[0].t = 1709164800.0 + 0.25;  // 2024/02/29 00:00:00.250
  in[1].t = 1735689599.9996;
  in[2].t = 1735689600.0021;
  write_rtklib_pos(dir_ / "c.pos", in);
  std::ifstream f(dir_ / "c.pos");
  std::string header, l0, l1, l2;
  std::getline(f, header);
  std::getline(f, l0);
  std::getline(f, l1);
  std::getline(f, l2);
  EXPECT_EQ(l0.substr(0, 23), "2024/02/29 00:00:00.250");
  EXPECT_EQ(l1.substr(0, 23), "2025/01/01 00:00:00.000");
  EXPECT_EQ(l2.substr(0, 23), "2025/01/01 00:00:00.002");
}

TEST_F(PosWrite, FixesRoundTripThroughTheirCovariance) {
  std::vector<GnssFix> fixes(2);
  for (std::size_t i = 0; i < 2; ++i) {
    auto& f = fixes[i];
    f.t = 1752003258.5 + 0.25 * static_cast<double>(i);
    f.frame = PositionFrame::geodetic;
    f.position = {40.1, -105.2, 1600.5};
    f.cov << 0.04, -0.01, 0.002, -0.01, 0.09, 0.003, 0.002, 0.003, 0.25;
    f.velocity = Eigen::Vector3d(3.0, -4.0, 0.1);
    f.velocity_cov = Eigen::Matrix3d::Identity() * 0.0025;
    f.velocity_cov(0, 1) = f.velocity_cov(1, 0) = -0.0004;
    f.quality = i ? FixQuality::floating : FixQuality::fixed;
    f.satellites_used = 17;
  }
  write_rtklib_pos(dir_ / "f.pos", fixes);
  const auto back = to_gnss_fixes(read_rtklib_pos(dir_ / "f.pos"));
  ASSERT_EQ(back.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_NEAR(back[i].t, fixes[i].t, 1e-6);
    EXPECT_EQ(back[i].position, fixes[i].position);  // exact in 9 and 4 decimals
    EXPECT_EQ(back[i].quality, fixes[i].quality);
    EXPECT_EQ(back[i].satellites_used, 17);
    // sd to 1e-4 m: a term c = s*|s| comes back within 2 * |s| * 5e-5.
    EXPECT_LT((back[i].cov - fixes[i].cov).cwiseAbs().maxCoeff(), 2 * 0.5 * 5e-5);
    ASSERT_TRUE(back[i].velocity.has_value());
    EXPECT_EQ(*back[i].velocity, *fixes[i].velocity);
    EXPECT_LT((back[i].velocity_cov - fixes[i].velocity_cov).cwiseAbs().maxCoeff(), 2 * 0.05 * 5e-6);
  }
  fixes[1].frame = PositionFrame::local_enu;
  EXPECT_THROW(write_rtklib_pos(dir_ / "g.pos", fixes), std::invalid_argument);
}

TEST_F(PosWrite, RefusesWhatTheReaderWouldRefuse) {
  const auto ok = random_records(3, 3);
  auto with = [&](auto change) {
    auto v = ok;
    change(v);
    return v;
  };
  const auto p = dir_ / "bad.pos";
  EXPECT_THROW(write_rtklib_pos(p, with([](auto& v) { v[1].t = v[0].t + 0.0004; })), std::invalid_argument);
  EXPECT_THROW(write_rtklib_pos(p, with([](auto& v) { v[1].latitude_deg = 91.0; })), std::invalid_argument);
  EXPECT_THROW(write_rtklib_pos(p, with([](auto& v) { v[2].sdu_m = std::nan(""); })), std::invalid_argument);
  EXPECT_THROW(write_rtklib_pos(p, with([](auto& v) { v[2].ratio = kUnknown; })), std::invalid_argument);
  EXPECT_THROW(write_rtklib_pos(p, with([](auto& v) { v[0].q = 8; })), std::invalid_argument);
  EXPECT_THROW(write_rtklib_pos(p, with([](auto& v) { v[0].t = 100.0; })), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(p));
}

// The drive's file rewritten: its 7-decimal positions, heights, Q, ns and velocities come back
// exactly; its 7-decimal sd columns to the 4 decimals this writer keeps.
TEST_F(PosWrite, RealDriveRewritten) {
  CTXFUSE_REQUIRE_DATA(pos_path, "gnss-imu-drive/gnss_1934_sf.pos");
  const auto a = read_rtklib_pos(pos_path);
  write_rtklib_pos(dir_ / "drive.pos", a.records);
  const auto b = read_rtklib_pos(dir_ / "drive.pos");
  ASSERT_EQ(b.records.size(), a.records.size());
  EXPECT_EQ(b.columns, a.columns);
  for (std::size_t i = 0; i < a.records.size(); ++i) {
    const auto &x = a.records[i], &y = b.records[i];
    ASSERT_EQ(y.t, x.t) << i;
    ASSERT_EQ(y.latitude_deg, x.latitude_deg) << i;
    ASSERT_EQ(y.longitude_deg, x.longitude_deg) << i;
    ASSERT_EQ(y.height_m, x.height_m) << i;
    ASSERT_EQ(y.q, x.q);
    ASSERT_EQ(y.ns, x.ns);
    ASSERT_EQ(y.vn_mps, x.vn_mps);
    ASSERT_EQ(y.vu_mps, x.vu_mps);
    ASSERT_NEAR(y.sdn_m, x.sdn_m, 5e-5 + 1e-12);
    ASSERT_NEAR(y.sdvu_mps, x.sdvu_mps, 5e-6 + 1e-12);
  }
}

}  // namespace

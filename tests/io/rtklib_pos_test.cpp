// RTKLIB .pos reader on small files written here: values, header-driven layout, the signed
// covariance terms, and every malformed case with its file:line:column.
#include <gtest/gtest.h>

#include <ctxfuse/io/rtklib_pos.hpp>

#include <cmath>
#include <string>

#include "temp_files.hpp"

namespace {

using namespace ctxfuse::io;
using namespace ctxfuse::messages;
using Pos = ctxfuse::test::TempFiles;

const std::string kFullHeader =
    "% program   : RTKLIB ver.demo5\n"
    "% obs start : 2025/07/08 19:34:18.5 GPST (week2374 239658.5s)\n"
    "%\n"
    "%  GPST            latitude(deg) longitude(deg) height(m) Q  ns  sdn(m)  sde(m)  sdu(m)  sdne(m)  sdeu(m)  "
    "sdun(m) age(s) ratio vn(m/s) ve(m/s) vu(m/s) sdvn sdve sdvu sdvne sdveu sdvun\n";

std::string epoch(const std::string& time, const std::string& lat = "40.0966268", const std::string& q = "1",
                  const std::string& sdn = "0.0200") {
  return "2025/07/08 " + time + " " + lat + " -105.1474483 1601.4740000 " + q + " 21 " + sdn +
         " 0.0300 0.0400 -0.0100 0.0050 0.0000 0.5 3.2 0.0100 -0.0020 0.0090 0.05 0.06 0.07 0.01 -0.02 0.0\n";
}

TEST_F(Pos, ReadsEveryColumnAndConvertsToFix) {
  const auto p = write("a.pos", kFullHeader + epoch("19:34:18.499") + "\r\n" +
                                    "2025/07/08 19:34:18.749 40.1 -105.2 1600.0 2.0000000 9.0000000 0.1 0.2 0.3 "
                                    "0.0 0.0 0.0 1.5 0.0 1.0 2.0 3.0 0.1 0.1 0.1 0.0 0.0 0.0\r\n");
  const auto file = read_rtklib_pos(p);
  ASSERT_EQ(file.records.size(), 2u);
  ASSERT_EQ(file.columns.size(), 22u);
  EXPECT_EQ(file.columns.front(), "latitude(deg)");
  const auto& r = file.records[0];
  EXPECT_NEAR(r.t, 1752003258.499, 1e-6);  // 2025-07-08 19:34:18 GPST = 1752003258 s on the 1970 scale
  EXPECT_NEAR(file.records[1].t - r.t, 0.25, 1e-6);
  EXPECT_EQ(r.latitude_deg, 40.0966268);
  EXPECT_EQ(r.longitude_deg, -105.1474483);
  EXPECT_EQ(r.height_m, 1601.474);
  EXPECT_EQ(r.q, 1);
  EXPECT_EQ(r.ns, 21);
  EXPECT_EQ(r.sdn_m, 0.02);
  EXPECT_EQ(r.sdne_m, -0.01);
  EXPECT_EQ(r.age_s, 0.5);
  EXPECT_EQ(r.ratio, 3.2);
  EXPECT_EQ(r.vn_mps, 0.01);
  EXPECT_EQ(r.sdveu_mps, -0.02);
  EXPECT_EQ(r.line, 5u);
  EXPECT_EQ(file.records[1].q, 2);
  EXPECT_EQ(file.records[1].ns, 9);
  EXPECT_EQ(file.records[1].line, 7u);

  const GnssFix fix = to_gnss_fix(r);
  EXPECT_EQ(fix.t, r.t);
  EXPECT_EQ(fix.frame, PositionFrame::geodetic);
  EXPECT_EQ(fix.position, Eigen::Vector3d(40.0966268, -105.1474483, 1601.474));
  EXPECT_EQ(fix.quality, FixQuality::fixed);
  EXPECT_EQ(fix.satellites_used, 21);
  // East/north/up: sde^2, sdn^2, sdu^2; the cross terms are sign * square.
  EXPECT_EQ(fix.cov(0, 0), 0.03 * 0.03);
  EXPECT_EQ(fix.cov(1, 1), 0.02 * 0.02);
  EXPECT_EQ(fix.cov(2, 2), 0.04 * 0.04);
  EXPECT_EQ(fix.cov(0, 1), -(0.01 * 0.01));
  EXPECT_EQ(fix.cov(1, 0), -(0.01 * 0.01));
  EXPECT_EQ(fix.cov(0, 2), 0.005 * 0.005);
  EXPECT_EQ(fix.cov(1, 2), 0.0);
  ASSERT_TRUE(fix.velocity.has_value());
  EXPECT_EQ(*fix.velocity, Eigen::Vector3d(-0.002, 0.01, 0.009));
  EXPECT_EQ(fix.velocity_cov(0, 0), 0.06 * 0.06);
  EXPECT_EQ(fix.velocity_cov(1, 1), 0.05 * 0.05);
  EXPECT_EQ(fix.velocity_cov(0, 1), 0.01 * 0.01);
  EXPECT_EQ(fix.velocity_cov(0, 2), -(0.02 * 0.02));
  EXPECT_EQ(to_gnss_fixes(file)[1].quality, FixQuality::floating);
}

TEST_F(Pos, LayoutComesFromTheHeader) {
  // No sd or velocity columns, ratio before ns: the reader must not assume positions.
  const auto p = write("b.pos", "%  GPST  latitude(deg) longitude(deg)  height(m)   Q  ratio  ns\n"
                                "2025/01/01 00:00:00.000 1.5 2.5 3.5 5 7.5 6\n");
  const auto file = read_rtklib_pos(p);
  ASSERT_EQ(file.records.size(), 1u);
  const auto& r = file.records[0];
  EXPECT_EQ(r.t, 1735689600.0);  // 2025-01-01 00:00:00
  EXPECT_EQ(r.ratio, 7.5);
  EXPECT_EQ(r.ns, 6);
  EXPECT_TRUE(std::isnan(r.sdn_m));
  EXPECT_FALSE(r.has_velocity());
  const auto fix = to_gnss_fix(r);
  EXPECT_EQ(fix.quality, FixQuality::single);
  EXPECT_TRUE(fix.cov.array().isNaN().all());  // no invented accuracy
  EXPECT_FALSE(fix.velocity.has_value());
}

TEST_F(Pos, MalformedEpochsNameFileLineColumn) {
  const std::string ok = kFullHeader + epoch("19:34:18.499");  // data starts at line 5, so the bad one is line 6
  EXPECT_PARSE_ERROR(read_rtklib_pos(write("count.pos", ok + "2025/07/08 19:34:18.749 40.0 -105.0 1600 1 21\n")),
                     "count.pos:6: ", "7 fields, expected 24 (as in the header)");
  EXPECT_PARSE_ERROR(read_rtklib_pos(write("nan.pos", ok + epoch("19:34:18.749", "40.09x"))),
                     "nan.pos:6:3: column 'latitude(deg)'", "'40.09x' has characters after the number");
  EXPECT_PARSE_ERROR(read_rtklib_pos(write("word.pos", ok + epoch("19:34:18.749", "north"))),
                     "word.pos:6:3: column 'latitude(deg)'", "'north' is not a number");
  EXPECT_PARSE_ERROR(read_rtklib_pos(write("inf.pos", ok + epoch("19:34:18.749", "40.0", "1", "inf"))),
                     "inf.pos:6:8: column 'sdn(m)'", "'inf' is not finite");
  EXPECT_PARSE_ERROR(read_rtklib_pos(write("neg.pos", ok + epoch("19:34:18.749", "40.0", "1", "-0.1"))),
                     "neg.pos:6:8: column 'sdn(m)'", "'-0.1' outside [0, 1e+06]");
  EXPECT_PARSE_ERROR(read_rtklib_pos(write("lat.pos", ok + epoch("19:34:18.749", "91.0"))),
                     "lat.pos:6:3: column 'latitude(deg)'", "outside [-90, 90]");
  EXPECT_PARSE_ERROR(read_rtklib_pos(write("q.pos", ok + epoch("19:34:18.749", "40.0", "9"))),
                     "q.pos:6:6: column 'Q'", "'9' is outside the allowed range [0, 7]");
  EXPECT_PARSE_ERROR(read_rtklib_pos(write("qf.pos", ok + epoch("19:34:18.749", "40.0", "1.5"))),
                     "qf.pos:6:6: column 'Q'", "is not a whole number");
  EXPECT_PARSE_ERROR(read_rtklib_pos(write("back.pos", ok + epoch("19:34:18.499"))), "back.pos:6:2: column 'GPST'",
                     "epoch is not after the previous one (line 5)");
  EXPECT_PARSE_ERROR(read_rtklib_pos(write("time.pos", ok + epoch("19:34"))), "time.pos:6:2: column 'GPST'",
                     "'19:34' is not a hh:mm:ss.sss time");
  EXPECT_PARSE_ERROR(read_rtklib_pos(write("date.pos", kFullHeader + "2025/02/30 " + epoch("1").substr(11))),
                     "date.pos:5:1: column 'GPST'", "'2025/02/30' is not a calendar date");
  EXPECT_PARSE_ERROR(read_rtklib_pos(write("utc.pos", "%  UTC  latitude(deg) longitude(deg) height(m) Q ns\n")),
                     "utc.pos:1: ", "time system UTC");
  EXPECT_PARSE_ERROR(read_rtklib_pos(write("ecef.pos", "%  GPST  x-ecef(m) y-ecef(m) z-ecef(m) Q ns\n")),
                     "ecef.pos:1: ", "only latitude/longitude/height");
  EXPECT_PARSE_ERROR(read_rtklib_pos(write("noq.pos", "%  GPST  latitude(deg) longitude(deg) height(m) ns\n")),
                     "noq.pos:1: ", "header has no column 'Q'");
  EXPECT_PARSE_ERROR(read_rtklib_pos(write("nohdr.pos", epoch("19:34:18.499"))), "nohdr.pos:1: ",
                     "data before the '%  GPST ...' column header");
  EXPECT_PARSE_ERROR(read_rtklib_pos(write("empty.pos", "% comment only\n")), "empty.pos: ", "no '%  GPST ...' column header");
  EXPECT_PARSE_ERROR(read_rtklib_pos(dir_ / "absent.pos"), "absent.pos: ", "cannot open file");
}

}  // namespace

// Every text reader on a valid file cut at every byte (zero bytes, mid-header, mid-line, on a
// line end): either the records of the whole lines before the cut, exactly as the uncut file
// gives them, with the cut line skipped and counted, or io::ParseError naming the file.
// (The IMU csv and time tag: imu_tag_partial_test.cpp; the Hanyang reader and the simulator's
// logs: hanyang_sim_partial_test.cpp.)
#include <gtest/gtest.h>

#include <ctxfuse/io/mag_csv.hpp>
#include <ctxfuse/io/nmea.hpp>
#include <ctxfuse/io/rtklib_pos.hpp>
#include <ctxfuse/io/uwb_static.hpp>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <algorithm>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "temp_files.hpp"

namespace {

using namespace ctxfuse::io;
using namespace ctxfuse::messages;
using Partial = ctxfuse::test::TempFiles;

using ctxfuse::test::slurp;
using ctxfuse::test::whole_lines;
bool at_line_end(const std::string& text, std::size_t cut) { return cut == 0 || text[cut - 1] == '\n'; }

/// NaN-aware exact equality of doubles.
bool same_or_nan(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

TEST_F(Partial, RtklibPosAtEveryByte) {
  std::vector<RtklibPosRecord> in(6);
  for (std::size_t i = 0; i < in.size(); ++i) {
    auto& r = in[i];
    const double k = static_cast<double>(i);
    r.t = 1752003258.499 + 0.25 * k;
    r.latitude_deg = 40.096626812 + 1e-7 * k;
    r.longitude_deg = -105.147448347 - 3e-7 * k;
    r.height_m = 1601.4741 + 0.0123 * k;
    r.q = i == 3 ? 2 : 1;
    r.ns = 21;
    r.sdn_m = r.sde_m = 0.0099 + 0.0011 * k;
    r.sdu_m = 0.0187;
    r.sdne_m = -0.0031;
    r.sdeu_m = r.sdun_m = 0.0012;
    r.age_s = 0.0;
    r.ratio = 12.3 + k;
    r.vn_mps = 0.01234 + k;
    r.ve_mps = -0.00213 - k;
    r.vu_mps = 0.00912;
    r.sdvn_mps = r.sdve_mps = r.sdvu_mps = 0.05869;
    r.sdvne_mps = r.sdveu_mps = 0.0;
    r.sdvun_mps = 0.05869 + 0.00111 * k;  // the last column: a cut "0.0" must not be read
  }
  const auto path = dir_ / "full.pos";
  write_rtklib_pos(path, in, {.velocity = true, .comments = {"ctxfuse partial-file test"}});
  const std::string text = slurp(path);
  const auto full = read_rtklib_pos(path);
  ASSERT_EQ(full.records.size(), 6u);
  const std::size_t header_lines = 2;
  for (std::size_t cut = 0; cut <= text.size(); ++cut) {
    SCOPED_TRACE("cut at byte " + std::to_string(cut));
    const auto p = write("cut.pos", text.substr(0, cut));
    const std::size_t lines = whole_lines(text, cut);
    RtklibPosFile got;
    try {
      got = read_rtklib_pos(p);
    } catch (const ParseError& e) {
      // Refused only while the column header is incomplete, and naming the file.
      EXPECT_LT(lines, header_lines) << e.what();
      EXPECT_EQ(e.file(), p.string());
      continue;
    }
    const std::size_t expect = lines > header_lines ? lines - header_lines : 0;
    ASSERT_EQ(got.records.size(), expect);
    EXPECT_EQ(got.skipped_partial_last_line, lines >= header_lines && !at_line_end(text, cut));
    for (std::size_t i = 0; i < expect; ++i) {
      const auto &a = full.records[i], &b = got.records[i];
      ASSERT_EQ(a.line, b.line);
      ASSERT_EQ(a.t, b.t);
      ASSERT_EQ(a.q, b.q);
      ASSERT_EQ(a.ns, b.ns);
      for (const auto& c : ctxfuse::io::detail::kPosColumns) ASSERT_TRUE(same_or_nan(a.*(c.member), b.*(c.member))) << c.name;
    }
  }
}

TEST_F(Partial, MagCsvAtEveryByte) {
  std::string text = "t,mag_x,mag_y,mag_z\n";
  for (int i = 0; i < 8; ++i) {
    char line[128];
    std::snprintf(line, sizeof line, "%.3f,%.4f,%.4f,%.4f\n", 1752003260.125 + 0.05 * i, 21.3125 - 0.25 * i, -3.0625 + i,
                  40.8125 + 0.125 * i);
    text += line;
  }
  const auto full = read_mag_csv(write("full.csv", text));
  ASSERT_EQ(full.size(), 8u);
  for (std::size_t cut = 0; cut <= text.size(); ++cut) {
    SCOPED_TRACE("cut at byte " + std::to_string(cut));
    const auto p = write("cut.csv", text.substr(0, cut));
    const std::size_t lines = whole_lines(text, cut);
    MagCsvReadStats stats;
    std::vector<MagSample> got;
    try {
      got = read_mag_csv(p, &stats);
    } catch (const ParseError& e) {
      EXPECT_EQ(lines, 0u) << e.what();  // an empty or cut header
      EXPECT_EQ(e.file(), p.string());
      continue;
    }
    const std::size_t expect = lines > 1 ? lines - 1 : 0;
    ASSERT_EQ(got.size(), expect);
    EXPECT_EQ(stats.skipped_partial_last_line, lines >= 1 && !at_line_end(text, cut));
    for (std::size_t i = 0; i < expect; ++i) {
      ASSERT_EQ(got[i].t, full[i].t);
      ASSERT_EQ(got[i].field_ut, full[i].field_ut);
    }
  }
}

TEST_F(Partial, UwbStaticAtEveryByte) {
  const std::string header = "timestamp,Distance,RSSI(dBm),RSSI_fp(dBm),anchor_id\n";
  std::string text = header;
  for (int i = 0; i < 6; ++i)
    text += "1723723564." + std::to_string(30 + i) + "," + std::to_string(10.07 + 0.01 * i) + ",-79.7" + std::to_string(i) +
            ",-80.7" + std::to_string(i) + ",12.0\n";
  text += "Distance Mean,10.095\nDistance Std,0.017\n";
  const auto dir = dir_ / "LOS" / "height_50.0cm";
  std::filesystem::create_directories(dir);
  auto read = [&](const std::string& body, ctxfuse::io::UwbStaticReadStats& stats) {
    std::ofstream(dir / "10m.csv", std::ios::binary) << body;
    return ctxfuse::io::read_uwb_static_file(dir / "10m.csv", 10.0, false, 50.0, stats);
  };
  ctxfuse::io::UwbStaticReadStats full_stats;
  const auto full = read(text, full_stats);
  ASSERT_EQ(full.size(), 6u);
  const std::size_t data_end = text.find("Distance Mean");
  for (std::size_t cut = 0; cut <= text.size(); ++cut) {
    SCOPED_TRACE("cut at byte " + std::to_string(cut));
    const std::size_t lines = whole_lines(text, cut);
    ctxfuse::io::UwbStaticReadStats stats;
    std::vector<ctxfuse::io::UwbStaticRange> got;
    try {
      got = read(text.substr(0, cut), stats);
    } catch (const ParseError& e) {
      EXPECT_EQ(lines, 0u) << e.what();  // no whole header
      EXPECT_NE(std::string(e.what()).find("10m.csv"), std::string::npos);
      continue;
    }
    const std::size_t expect = cut >= data_end ? 6 : (lines > 1 ? lines - 1 : 0);
    ASSERT_EQ(got.size(), expect);
    EXPECT_EQ(stats.skipped_partial_last_lines, cut < data_end && lines >= 1 && !at_line_end(text, cut) ? 1u : 0u);
    for (std::size_t i = 0; i < expect; ++i) {
      ASSERT_EQ(got[i].measured_distance_m, full[i].measured_distance_m);
      ASSERT_EQ(got[i].rssi_dbm, full[i].rssi_dbm);
      ASSERT_EQ(got[i].first_path_rssi_dbm, full[i].first_path_rssi_dbm);
    }
  }
}

// NMEA: "$" + body + "*" + checksum.
std::string sentence(const std::string& body) {
  unsigned char sum = 0;
  for (const char c : body) sum ^= static_cast<unsigned char>(c);
  char tail[8];
  std::snprintf(tail, sizeof tail, "*%02X\n", sum);
  return "$" + body + tail;
}

TEST_F(Partial, NmeaAtEveryByte) {
  namespace nmea = ctxfuse::io::nmea;
  std::string text;
  for (int e = 0; e < 3; ++e) {
    const std::string tod = "02141" + std::to_string(7 + e) + ".00";
    text += sentence("GNRMC," + tod + ",A,3725.58362,N,12205.61915,W,0.028,65.13,070220,13.06,E,F,V");
    text += sentence("GNGGA," + tod + ",3725.58362,N,12205.61915,W,5,12,0.76,4.4,M,-30.0,M,0.0,2000");
    text += sentence("GNGSA,A,3,17,02,06,28,12,13,15,24,19,,,,1.4" + std::to_string(e) + ",0.76,1.27,1");
    text += sentence("GPGSV,2,1,06,02,25,181,42,06,45,146,45,12,19,292,47,13,17,209,4" + std::to_string(e) + ",1");
    text += sentence("GPGSV,2,2,06,15,16,241,47,17,52,040,46,1");
    text += sentence("GNGLL,3725.58362,N,12205.61915,W," + tod + ",A,D");
  }
  std::istringstream whole(text);
  const auto full = nmea::parse_nmea(whole);
  ASSERT_EQ(full.epochs.size(), 3u);
  ASSERT_EQ(full.epochs[2].satellites.size(), 6u);
  // b equals a; or, for an epoch partly read, holds a's time and a prefix of the rest.
  auto same_epoch = [](const nmea::NmeaEpoch& a, const nmea::NmeaEpoch& b, bool partial) {
    if (!same_or_nan(a.time_s, b.time_s)) return false;
    if (!(partial && std::isnan(b.pdop)) && !same_or_nan(a.pdop, b.pdop)) return false;
    if (!(partial && !b.gga) && a.gga.has_value() != b.gga.has_value()) return false;
    if (b.gga && (!a.gga || a.gga->quality != b.gga->quality || a.gga->latitude_deg != b.gga->latitude_deg ||
                  a.gga->longitude_deg != b.gga->longitude_deg || a.gga->satellites_used != b.gga->satellites_used))
      return false;
    if (partial ? b.satellites.size() > a.satellites.size() : b.satellites.size() != a.satellites.size()) return false;
    for (std::size_t i = 0; i < b.satellites.size(); ++i)
      if (a.satellites[i].prn != b.satellites[i].prn || !same_or_nan(a.satellites[i].snr_dbhz, b.satellites[i].snr_dbhz))
        return false;
    return true;
  };
  const std::size_t lines_per_epoch = 6;
  for (std::size_t cut = 0; cut <= text.size(); ++cut) {
    SCOPED_TRACE("cut at byte " + std::to_string(cut));
    std::istringstream in(text.substr(0, cut));
    const auto got = nmea::parse_nmea(in);  // never throws on content
    // A sentence whole but for its newline passes its checksum: it counts as whole.
    const bool whole_sentence = cut < text.size() && text[cut] == '\n';
    const std::size_t lines = whole_lines(text, cut) + whole_sentence, done = lines / lines_per_epoch,
                      in_epoch = lines % lines_per_epoch;
    const bool mid = !at_line_end(text, cut) && !whole_sentence;
    // Epochs kept: the whole ones; at a sentence boundary also a partial one outside its GSV
    // sequence. Cut inside a sentence: the current epoch is dropped unless that sentence is
    // the next epoch's RMC with its time whole ("$GNRMC,021418.00," is 17 characters).
    std::size_t expect = done;
    if (!mid && in_epoch > 0 && in_epoch != 4) expect = done + 1;
    if (mid && in_epoch == 0 && done > 0 && cut - (text.rfind('\n', cut - 1) + 1) < 17) expect = done - 1;
    ASSERT_EQ(got.epochs.size(), expect) << "in epoch " << in_epoch << (mid ? ", mid-line" : "");
    EXPECT_EQ(got.stats.dropped_incomplete_last_epoch, expect < done || (expect == done && in_epoch == 4) ||
                                                           (expect == done && mid && in_epoch > 0));
    for (std::size_t i = 0; i < std::min(expect, done); ++i) ASSERT_TRUE(same_epoch(full.epochs[i], got.epochs[i], false)) << i;
    if (expect == done + 1) {
      EXPECT_TRUE(same_epoch(full.epochs[done], got.epochs[done], true));
    }
  }
}

}  // namespace

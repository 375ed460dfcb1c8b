// NMEA reader: checksums, epoch assembly, multi-signal GSV, malformed sentences, distances.
#include <gtest/gtest.h>

#include <ctxfuse/io/nmea.hpp>
#include <ctxfuse/features/scene_label.hpp>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

namespace {

using namespace ctxfuse::features;
using namespace ctxfuse::io;
using namespace ctxfuse::io::nmea;

// Appends "*hh" computed here by XOR (the test's own reference for the checksum).
std::string with_checksum(const std::string& body) {
  unsigned char x = 0;
  for (char c : body.substr(1)) x ^= static_cast<unsigned char>(c);
  char buf[8];
  std::snprintf(buf, sizeof buf, "*%02X", x);
  return body + buf;
}

TEST(Nmea, ChecksumOfRealSentences) {
  // Sentences copied from a u-blox log; the checksums are the receiver's.
  EXPECT_TRUE(checksum_ok("$GNGGA,021417.00,3725.58362,N,12205.61915,W,5,12,0.76,4.4,M,-30.0,M,0.0,2000*52"));
  EXPECT_TRUE(checksum_ok("$GNGSA,A,3,80,83,73,84,82,,,,,,,,1.48,0.76,1.27,2*0B\r\n"));
  EXPECT_FALSE(checksum_ok("$GNGSA,A,3,80,83,73,84,82,,,,,,,,1.48,0.76,1.27,2*0C"));
  EXPECT_FALSE(checksum_ok("$GNGSA,A,3,80,83,73,84,82,,,,,,,,1.48,0.76,1.27,2"));
  EXPECT_FALSE(checksum_ok("$GNGSA*Z1"));
  EXPECT_FALSE(checksum_ok(""));
}

TEST(Nmea, AssemblesEpochsAndKeepsL1Signals) {
  std::ostringstream log;
  log << with_checksum("$GNRMC,235959.00,A,3725.58362,N,12205.61915,W,0.028,65.13,070220,13.06,E,F,V") << '\n'
      << with_checksum("$GNGGA,235959.00,3725.50000,N,12205.60000,W,4,12,0.76,4.4,M,-30.0,M,0.0,2000") << '\n'
      << with_checksum("$GNGSA,A,3,17,02,06,,,,,,,,,,1.48,0.76,1.27,1") << '\n'
      // GPS L1 (signal 1): two satellites, one untracked; then the same satellites on L2 (6)
      << with_checksum("$GPGSV,1,1,02,02,25,181,42,06,45,146,,1") << '\n'
      << with_checksum("$GPGSV,1,1,02,02,25,181,30,06,45,146,33,6") << '\n'
      // Galileo E1 is signal 7; E5b (2) is ignored
      << with_checksum("$GAGSV,1,1,01,11,11,201,35,7") << '\n'
      << with_checksum("$GAGSV,1,1,01,11,11,201,40,2") << '\n'
      // GLONASS without signal id (NMEA 4.0), a padding group and one without elevation
      << with_checksum("$GLGSV,1,1,03,65,01,331,35,,,,53,70,,,20") << '\n'
      << "$GPGSV,1,1,01,02,25,181,42,1*00\n"                                   // bad checksum
      << with_checksum("$GPGSV,1,1,01,02,95,181,42,1") << '\n'                 // elevation 95
      << with_checksum("$GNVTG,65.13,T,52.07,M,0.028,N,0.053,K,D") << '\n'     // ignored type
      // Next epoch after midnight: time of day wraps.
      << with_checksum("$GNGGA,000000.00,3725.50000,N,12205.60000,W,0,00,99.99,,,,,,") << '\n'
      << with_checksum("$GNGSA,A,1,,,,,,,,,,,,,99.99,99.99,99.99,1") << '\n';
  std::istringstream in(log.str());
  const NmeaLog parsed = parse_nmea(in);
  ASSERT_EQ(parsed.epochs.size(), 2u);
  const auto& e0 = parsed.epochs[0];
  EXPECT_DOUBLE_EQ(e0.time_s, 86399.0);
  ASSERT_TRUE(e0.gga.has_value());
  EXPECT_EQ(e0.gga->quality, 4);
  EXPECT_NEAR(e0.gga->latitude_deg, 37.0 + 25.5 / 60.0, 1e-12);
  EXPECT_NEAR(e0.gga->longitude_deg, -(122.0 + 5.6 / 60.0), 1e-12);
  EXPECT_DOUBLE_EQ(e0.pdop, 1.48);
  ASSERT_EQ(e0.satellites.size(), 4u);  // G02, G06, E11, R65
  EXPECT_EQ(e0.satellites[0].prn, 2);
  EXPECT_DOUBLE_EQ(e0.satellites[0].snr_dbhz, 42.0);  // L1, not the L2 value 30
  EXPECT_TRUE(std::isnan(e0.satellites[1].snr_dbhz));
  EXPECT_EQ(e0.satellites[2].system, GnssSystem::galileo);
  EXPECT_DOUBLE_EQ(e0.satellites[2].snr_dbhz, 35.0);
  EXPECT_EQ(e0.satellites[3].system, GnssSystem::glonass);
  EXPECT_DOUBLE_EQ(e0.satellites[3].azimuth_deg, 331.0);

  const auto& e1 = parsed.epochs[1];
  EXPECT_DOUBLE_EQ(e1.time_s, 86400.0);
  EXPECT_EQ(e1.gga->quality, 0);
  EXPECT_FALSE(e1.gga->has_position());
  EXPECT_TRUE(std::isnan(e1.pdop));  // 99.99 = no DOP

  EXPECT_EQ(parsed.stats.checksum_failures, 1u);
  EXPECT_EQ(parsed.stats.malformed, 1u);
  EXPECT_EQ(parsed.stats.ignored, 1u);
  EXPECT_EQ(parsed.stats.satellites_without_geometry, 1u);
  ASSERT_EQ(parsed.stats.first_problems.size(), 2u);
  EXPECT_EQ(parsed.stats.first_problems[0].line, 9u);
  EXPECT_EQ(parsed.stats.first_problems[1].line, 10u);
  EXPECT_EQ(parsed.stats.first_problems[0].column, 0u);  // a checksum is the sentence's
  EXPECT_EQ(parsed.stats.first_problems[1].column, 6u);  // GPGSV,1,1,01,02,95: the sixth field
  EXPECT_EQ(parsed.stats.first_problems[1].message, "GSV column 6 'elevation': '95' does not parse");
}

TEST(Nmea, GarbageNeverThrows) {
  std::istringstream in(std::string("\x01\x02garbage\n$\n*\n$GPGGA*00\n$,,,*") + "\n" +
                        with_checksum("$GPGGA,12") + "\n" + with_checksum("$GPGSV,a,b,c") + "\n" +
                        with_checksum("$GPGSV,1,1,01,02,25") + "\n" + with_checksum("$TOOLONGGGA,1"));
  NmeaLog parsed;
  ASSERT_NO_THROW(parsed = parse_nmea(in));
  EXPECT_TRUE(parsed.epochs.empty());
  EXPECT_EQ(parsed.stats.checksum_failures + parsed.stats.malformed, 9u);
}

TEST(Nmea, HorizontalDistanceMatchesDegreeLengthSeries) {
  // Degree lengths from the standard series (latitude 111132.92 - 559.82 cos 2p + 1.175 cos 4p,
  // longitude 111412.84 cos p - 93.5 cos 3p, metres per degree): at p = 45 deg,
  // 111131.745 and 78846.889; 0.001 deg of each.
  EXPECT_NEAR(horizontal_distance_m(45.0005, 0.0, 44.9995, 0.0), 111.131745, 1e-4);
  EXPECT_NEAR(horizontal_distance_m(45.0, 0.0005, 45.0, -0.0005), 78.846889, 1e-4);
  EXPECT_NEAR(horizontal_distance_m(45.0, 179.9995, 45.0, -179.9995), 78.846889, 1e-4);  // across 180
  EXPECT_NEAR(horizontal_distance_m(45.0003, 0.0004, 45.0, 0.0), std::hypot(0.3 * 111.131745, 0.4 * 78.846889), 1e-4);
}

TEST(SceneLabels, ThresholdsAndMissingData) {
  auto epoch = [](double t, int quality, double lat, double lon) {
    NmeaEpoch e;
    e.time_s = t;
    GgaFix g;
    g.quality = quality;
    g.latitude_deg = lat;
    g.longitude_deg = lon;
    e.gga = g;
    return e;
  };
  const double m = 1.0 / 111132.95 * 1.0;  // ~1 m of latitude at 45 deg, in degrees
  std::vector<NmeaEpoch> rx{epoch(0, 4, 45.0 + 0.5 * m, 0), epoch(1, 1, 45.0 + 3.5 * m, 0), epoch(2, 0, 0, 0),
                            epoch(3, 6, 45.0, 0), epoch(4, 4, 45.0, 0), epoch(6, 4, 45.0, 0)};
  rx.push_back(NmeaEpoch{});  // no time
  rx.back().time_s = 7;       // no GGA: unlabelled
  const std::vector<NmeaEpoch> ref{epoch(0, 1, 45.0, 0), epoch(1, 1, 45.0, 0), epoch(2, 1, 45.0, 0),
                                   epoch(3, 1, 45.0, 0), epoch(4.2, 1, 45.0, 0), epoch(6.02, 1, 45.0, 0),
                                   epoch(7, 1, 45.0, 0)};
  SceneLabelThresholds th;
  th.open_max_error_m = 2.0;
  const auto labels = label_scenes(rx, ref, th);
  ASSERT_EQ(labels.size(), 5u);  // t = 4 has no reference within 0.05 s, t = 7 has no GGA
  EXPECT_EQ(labels[0].label, scene_open);
  EXPECT_NEAR(labels[0].horizontal_error_m, 0.5, 1e-3);
  EXPECT_EQ(labels[1].label, scene_obstructed);
  EXPECT_EQ(labels[2].label, scene_no_position);
  EXPECT_EQ(labels[3].label, scene_no_position);  // dead reckoning
  EXPECT_EQ(labels[4].epoch_index, 5u);
  EXPECT_EQ(labels[4].label, scene_open);
}

}  // namespace

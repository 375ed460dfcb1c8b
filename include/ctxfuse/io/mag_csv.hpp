// Reader of a magnetometer csv beside a recording (`ctxfuse run gins --data DIR`: one optional
// mag*.csv), in the column layout of the simulator's mag.csv (docs/formats.md), so a simulated
// drive's file reads as a recording's:
//
//   t,mag_x,mag_y,mag_z            header, then one sample a line
//   1751990001.25,21.3,-3.1,40.8   t: GPS time [s] on RTKLIB's 1970-based scale, the time of the
//                                  .pos fixes (a simulated drive's own seconds in its mag.csv);
//                                  field: [microtesla] in the IMU's axes, so --imu-rpy rotates
//                                  it to the body frame as it does the IMU's samples
//
// The stamps are the magnetometer's own: the IMU's logging delay (--imu-delay) is not added.
// Rejected, as io::ParseError naming file, line and column: a wrong header, a wrong number of
// fields, text that is not a number, non-finite values, time that does not increase, and a
// field above 1000 uT in magnitude (the Earth's is 25-65 uT; a thousand is a unit error, e.g.
// nanotesla or gauss*1e3, or a magnet on the sensor, not a field to take a heading from).
// A last data line without a newline is not trusted (a cut "40.8" reads as "40."): it is
// skipped and counted in MagCsvReadStats.
#pragma once

#include <ctxfuse/messages/sensors.hpp>
#include <ctxfuse/io/text.hpp>

#include <filesystem>
#include <string_view>
#include <vector>

namespace ctxfuse::io {

inline constexpr std::string_view kMagCsvHeader = "t,mag_x,mag_y,mag_z";
inline constexpr double kMagCsvMaxFieldUt = 1000.0;

struct MagCsvReadStats {
  bool skipped_partial_last_line = false;
};

inline std::vector<messages::MagSample> read_mag_csv(const std::filesystem::path& path, MagCsvReadStats* stats = nullptr) {
  TextFile file(path);
  Fields f(file.name());
  std::vector<messages::MagSample> out;
  std::string_view line;
  bool header = false;
  while (file.next(line)) {
    if (trim(line).empty()) continue;
    if (!header) {
      if (trim(line) != kMagCsvHeader) file.fail(cat("expected the header '", kMagCsvHeader, "'"));
      header = true;
      continue;
    }
    if (!file.ended_by_newline()) {
      if (stats) stats->skipped_partial_last_line = true;
      break;
    }
    f.split(line, file.line_number(), Separator::comma);
    f.expect_count(4);
    messages::MagSample m;
    m.t = f.real(0);
    for (int k = 0; k < 3; ++k) m.field_ut[k] = f.real(static_cast<std::size_t>(1 + k));
    if (!out.empty() && !(m.t > out.back().t))
      f.fail(0, cat("time ", m.t, " is not after the previous sample's ", out.back().t, " (times must increase)"));
    if (!(m.field_ut.norm() <= kMagCsvMaxFieldUt))
      f.fail(1, cat("field magnitude ", m.field_ut.norm(), " uT is above ", kMagCsvMaxFieldUt, " uT (unit error?)"));
    out.push_back(m);
  }
  if (!header) file.fail("empty file: expected the header 't,mag_x,mag_y,mag_z'");
  return out;
}

}  // namespace ctxfuse::io

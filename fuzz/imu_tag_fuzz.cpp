// io/imu_tag.hpp: the input is split (fuzz_support.hpp, split2) into an IMU csv and a binary
// RTKLIB time-tag file; both are read, and when both are accepted they are mapped to
// samples. Accepted records must keep the reader's bounds; a mapped time must be finite
// whenever the clock could be built (the clock refuses a zero tick span).
#include <cmath>

#include "ctxfuse/io/imu_tag.hpp"
#include "fuzz_support.hpp"

namespace io = ctxfuse::io;
using ctxfuse_fuzz::fail;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto [csv_bytes, tag_bytes] = ctxfuse_fuzz::split2(data, size);
  const auto& s = ctxfuse_fuzz::scratch();
  const auto csv_path = s.write("imu.csv", csv_bytes);
  const auto tag_path = s.write("imu.csv.tag", tag_bytes);
  io::ImuCsvLog log;
  bool have_log = false;
  try {
    log = io::read_imu_csv(csv_path);
    have_log = true;
    for (const auto& r : log.records)
      if (!r.accel_g.allFinite() || !r.gyro_dps.allFinite() || r.tick_ms < 0) fail("accepted IMU record out of bounds");
  } catch (const io::ParseError&) {
  }
  io::TimeTag tag;
  bool have_tag = false;
  try {
    tag = io::read_time_tag(tag_path);
    have_tag = true;
    if (tag.records.empty()) fail("accepted a tag file without records");
    if (!(tag.start_fraction_s >= 0.0 && tag.start_fraction_s < 1.0)) fail("accepted a fraction outside [0, 1)");
  } catch (const io::ParseError&) {
  }
  if (!have_log || !have_tag) return 0;
  try {
    for (const auto& sample : io::to_imu_samples(log, tag))
      if (!std::isfinite(sample.t) || !sample.gyro.allFinite() || !sample.accel.allFinite())
        fail("non-finite IMU sample from accepted files");
  } catch (const io::ParseError&) {
  }
  return 0;
}

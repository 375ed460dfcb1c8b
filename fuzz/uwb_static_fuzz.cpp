// io/uwb_static.hpp: the split input (fuzz_support.hpp, split2) as a file name, through the
// name parser the dataset walk uses for heights and distances, and as one recording's csv.
// Accepted ranges must have a distance within the reader's [0, 1000] m and finite powers
// (non-finite ones are skipped and counted), and the counts must add up.
#include <cmath>

#include "ctxfuse/io/uwb_static.hpp"
#include "fuzz_support.hpp"

namespace io = ctxfuse::io;
using ctxfuse_fuzz::fail;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto [name, csv] = ctxfuse_fuzz::split2(data, size);
  (void)ctxfuse::io::detail::number_in_name(name, "height_", "cm");
  (void)ctxfuse::io::detail::number_in_name(name, "", "m.csv");
  const auto path = ctxfuse_fuzz::scratch().write("10m.csv", csv);
  ctxfuse::io::UwbStaticReadStats stats;
  try {
    const auto ranges = ctxfuse::io::read_uwb_static_file(path, 10.0, true, 50.0, stats);
    if (stats.files != 1 || stats.ranges != ranges.size()) fail("read statistics do not add up");
    for (const auto& r : ranges)
      if (!(r.measured_distance_m >= 0.0 && r.measured_distance_m <= 1000.0) || !std::isfinite(r.rssi_dbm) ||
          !std::isfinite(r.first_path_rssi_dbm))
        fail("accepted range out of bounds");
  } catch (const io::ParseError&) {
  }
  return 0;
}

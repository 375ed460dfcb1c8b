// io/nmea.hpp: the reader counts bad sentences instead of throwing, so any bytes must come
// back as a log, never as an exception or a crash (an escaping exception aborts the target);
// the stream and the file entry points must agree, and the kept problems stay capped.
#include <sstream>

#include "ctxfuse/io/nmea.hpp"
#include "fuzz_support.hpp"

namespace nmea = ctxfuse::io::nmea;
using ctxfuse_fuzz::fail;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  std::istringstream in(bytes);
  const auto log = nmea::parse_nmea(in);
  if (log.stats.first_problems.size() > nmea::NmeaStats::kMaxProblems) fail("more problems kept than the cap");
  const auto path = ctxfuse_fuzz::scratch().write("log.nmea", bytes);
  const auto again = nmea::read_nmea_file(path.string());
  if (again.epochs.size() != log.epochs.size() || again.stats.lines != log.stats.lines ||
      again.stats.malformed != log.stats.malformed)
    fail("file and stream readings of the same bytes differ");
  return 0;
}

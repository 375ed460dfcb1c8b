// sim/logs.hpp: a log folder in which one file (chosen by the first byte) holds the rest
// of the input and the others hold only their header; selector 7 splits the rest
// (fuzz_support.hpp, split2) into gnss.csv and sats.csv, whose epochs the reader
// cross-checks. The folder is then read as a pipeline reads it (read_sim_logs, which also
// converts to sensor messages). Accepted rows must have finite times in order.
#include <cmath>
#include <string>

#include "ctxfuse/sim/logs.hpp"
#include "fuzz_support.hpp"

namespace io = ctxfuse::io;
namespace csv = ctxfuse::sim::csv;
using ctxfuse_fuzz::fail;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const int selector = data[0] % 8;
  const std::string_view rest(reinterpret_cast<const char*>(data + 1), size - 1);
  const auto& s = ctxfuse_fuzz::scratch();
  const std::pair<const char*, const char*> files[] = {
      {"imu.csv", csv::kImuHeader},     {"gnss.csv", csv::kGnssHeader}, {"sats.csv", csv::kSatsHeader},
      {"uwb.csv", csv::kUwbHeader},     {"speed.csv", csv::kSpeedHeader}, {"mag.csv", csv::kMagHeader},
      {"truth.csv", csv::kTruthHeader}};
  for (int k = 0; k < 7; ++k) s.write(files[k].first, std::string(files[k].second) + "\n");
  if (selector < 7) {
    s.write(files[selector].first, rest);
  } else {
    const auto [gnss, sats] = ctxfuse_fuzz::split2(data + 1, size - 1);
    s.write("gnss.csv", gnss);
    s.write("sats.csv", sats);
  }
  try {
    const auto logs = ctxfuse::sim::read_sim_logs(s.dir());
    const auto& truth = logs.truth.truth;
    for (std::size_t i = 0; i < truth.size(); ++i) {
      if (!std::isfinite(truth[i].t)) fail("non-finite truth time accepted");
      if (i > 0 && !(truth[i].t > truth[i - 1].t)) fail("truth times not increasing");
    }
  } catch (const io::ParseError&) {
  }
  return 0;
}

// io/hanyang_uwb.hpp: a case folder made of the split input (fuzz_support.hpp, split2), the
// first part as the range file of anchor 3 (A3.csv), the second as trajectory.csv. Accepted
// ranges must be in time order, carry anchor 3 and a range within the reader's bounds;
// accepted reference poses must have increasing, finite times.
#include <cmath>

#include "ctxfuse/io/hanyang_uwb.hpp"
#include "fuzz_support.hpp"

namespace io = ctxfuse::io;
using ctxfuse_fuzz::fail;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto [ranges, trajectory] = ctxfuse_fuzz::split2(data, size);
  const auto& s = ctxfuse_fuzz::scratch();
  s.write("A3.csv", ranges);
  s.write("trajectory.csv", trajectory);
  try {
    const auto c = io::read_hanyang_uwb(s.dir());
    for (std::size_t i = 0; i < c.ranges.size(); ++i) {
      const auto& r = c.ranges[i];
      if (r.range.anchor_id != 3) fail("range of another anchor accepted from A3.csv");
      if (!(r.range.range_m >= 0.0 && r.range.range_m <= 1000.0) || !std::isfinite(r.range.t))
        fail("accepted range or time out of bounds");
      if (i > 0 && !(r.t_ns > c.ranges[i - 1].t_ns)) fail("accepted ranges out of time order");
    }
  } catch (const io::ParseError&) {
  }
  try {
    const auto poses = io::read_hanyang_reference(s.dir());
    for (std::size_t i = 0; i < poses.size(); ++i) {
      if (!std::isfinite(poses[i].t) || !poses[i].position.allFinite()) fail("non-finite reference pose accepted");
      if (i > 0 && !(poses[i].t > poses[i - 1].t)) fail("reference poses out of time order");
    }
  } catch (const io::ParseError&) {
  }
  return 0;
}

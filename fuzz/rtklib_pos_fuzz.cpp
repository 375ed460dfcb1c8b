// io/rtklib_pos.hpp: any bytes as a .pos file, then the conversion of what was read to GNSS
// fixes. The reader promises strictly increasing epochs and finite positions; the
// conversion must not produce a NaN position from a record the reader accepted.
#include <cmath>

#include "ctxfuse/io/rtklib_pos.hpp"
#include "fuzz_support.hpp"

namespace io = ctxfuse::io;
using ctxfuse_fuzz::fail;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = ctxfuse_fuzz::scratch().write("fix.pos", {reinterpret_cast<const char*>(data), size});
  io::RtklibPosFile file;
  try {
    file = io::read_rtklib_pos(path);
  } catch (const io::ParseError&) {
    return 0;
  }
  for (std::size_t i = 0; i < file.records.size(); ++i) {
    const auto& r = file.records[i];
    if (!std::isfinite(r.t) || !std::isfinite(r.latitude_deg) || !std::isfinite(r.longitude_deg) || !std::isfinite(r.height_m))
      fail("accepted record with a non-finite time or position");
    if (i > 0 && !(r.t > file.records[i - 1].t)) fail("accepted epochs that do not increase");
  }
  try {
    for (const auto& fix : io::to_gnss_fixes(file))
      if (!fix.position.allFinite()) fail("fix with a non-finite position");
  } catch (const io::ParseError&) {
  }
  return 0;
}

// pipelines/region_imm/recogniser_io.hpp: any bytes as a region recogniser file. A file the
// reader accepts must survive a round trip through the writer (written, read back and
// written again: the same text), since save/load is how a trained recogniser is shipped.
#include <sstream>
#include <string>

#include "ctxfuse/pipelines/region_imm/recogniser_io.hpp"
#include "fuzz_support.hpp"

namespace ri = ctxfuse::pipelines::region_imm;
using ctxfuse_fuzz::fail;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  ri::Recogniser r;
  try {
    r = ri::read_recogniser(in, "fuzz");
  } catch (const ri::RecogniserFileError&) {
    return 0;
  }
  std::ostringstream first;
  ri::write_recogniser(first, r);
  std::istringstream back(first.str());
  ri::Recogniser again;
  try {
    again = ri::read_recogniser(back, "fuzz (written back)");
  } catch (const ri::RecogniserFileError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    fail("an accepted recogniser, written by us, is refused by our reader");
  }
  std::ostringstream second;
  ri::write_recogniser(second, again);
  if (second.str() != first.str()) fail("write / read / write is not the identity");
  return 0;
}

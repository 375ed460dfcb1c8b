// io/text.hpp: the one splitter and number parser under every recorded-log reader. Besides
// "no crash, no sanitizer report", what the header promises is checked: a parsed real is
// finite and within the caller's bound unless non-finite values are allowed, a parsed
// integer is within [lo, hi], comma splitting keeps every field (commas + 1), whitespace
// splitting never yields an empty or blank-holding field; and no line ending's CR reaches
// a field of the line reader.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "ctxfuse/io/text.hpp"
#include "fuzz_support.hpp"

namespace io = ctxfuse::io;
using ctxfuse_fuzz::fail;

namespace {

void numbers(std::string_view field) {
  double v = 0.0;
  if (io::parse_real(field, v) == io::NumberError::none && !(std::isfinite(v) && std::abs(v) <= 1e19))
    fail("parse_real accepted a non-finite or too large value");
  const io::RealRules loose{true, 1e300};
  if (io::parse_real(field, v, loose) == io::NumberError::none && std::isfinite(v) && std::abs(v) > 1e300)
    fail("parse_real accepted a value above max_abs");
  // Full-range integer types: the bounds conversions are where overflow would hide.
  std::int64_t i64 = 0;
  if (io::parse_integer(field, i64) == io::NumberError::none) (void)i64;
  if (io::parse_whole(field, i64, std::numeric_limits<std::int64_t>::min(), std::numeric_limits<std::int64_t>::max()) ==
      io::NumberError::none)
    (void)i64;
  int i = 0;
  if (io::parse_integer(field, i, -5, 7) == io::NumberError::none && (i < -5 || i > 7))
    fail("parse_integer outside [lo, hi]");
  if (io::parse_whole(field, i, -5, 7) == io::NumberError::none && (i < -5 || i > 7))
    fail("parse_whole outside [lo, hi]");
  std::uint32_t u = 0;
  (void)io::parse_whole(field, u, 0u, std::numeric_limits<std::uint32_t>::max());
}

void splitting(std::string_view line) {
  const auto comma = io::split_fields(line, io::Separator::comma);
  if (comma.size() != static_cast<std::size_t>(std::count(line.begin(), line.end(), ',')) + 1)
    fail("comma split lost or invented a field");
  for (const auto f : io::split_fields(line, io::Separator::whitespace))
    if (f.empty() || std::any_of(f.begin(), f.end(), io::is_blank)) fail("whitespace split gave a blank field");
  for (const auto f : comma) numbers(f);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  numbers(bytes);
  splitting(bytes);
  // The line reader over the same bytes as a file, with typed field access as readers use it.
  const auto path = ctxfuse_fuzz::scratch().write("text.csv", bytes);
  try {
    io::TextFile file(path);
    io::Fields f(file.name());
    std::string_view line;
    while (file.next(line)) {
      f.split(line, file.line_number(), io::Separator::comma);
      // The promise is that a line ending's CR never reaches a field, not that the line has
      // none: "\r\r\n" keeps one CR in the line (input text_fuzz/cr-cr-lf), which trimming
      // removes from the last field.
      if (const auto last = f[f.size() - 1]; !last.empty() && last.back() == '\r') fail("a CR reached a field");
      for (std::size_t k = 0; k < f.size(); ++k) {
        try {
          (void)f.real_in(k, -1e6, 1e6);
        } catch (const io::ParseError&) {
        }
        try {
          (void)f.whole<std::int64_t>(k, std::numeric_limits<std::int64_t>::min(), std::numeric_limits<std::int64_t>::max());
        } catch (const io::ParseError&) {
        }
      }
    }
  } catch (const io::ParseError&) {
  }
  return 0;
}

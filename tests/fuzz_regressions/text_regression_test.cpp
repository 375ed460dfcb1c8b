// Findings of the fuzz targets that were bugs in the library, as expectations that fail on
// the code before the fix (the replay tests beside this file only show that nothing aborts).
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

#include "ctxfuse/io/text.hpp"

namespace {
using namespace ctxfuse::io;

// text_fuzz, input whole-2-pow-63: "9223372036854775808" is 2^63, one past INT64_MAX. It
// compared equal to double(INT64_MAX) (which rounds up to 2^63), passed the range check and
// was converted to int64 (undefined behaviour; on x86-64 it gave INT64_MIN).
TEST(FuzzRegressions, WholeNumberOnePastInt64MaxIsOutOfRange) {
  constexpr auto lo = std::numeric_limits<std::int64_t>::min(), hi = std::numeric_limits<std::int64_t>::max();
  std::int64_t v = 7;
  EXPECT_EQ(parse_whole<std::int64_t>("9223372036854775808", v, lo, hi), NumberError::out_of_range);
  EXPECT_EQ(parse_whole<std::int64_t>("9.3e18", v, lo, hi), NumberError::out_of_range);
  EXPECT_EQ(v, 7);  // untouched on failure
  // The largest double below 2^63 is 2^63 - 1024: it fits and is returned exactly.
  ASSERT_EQ(parse_whole<std::int64_t>("9223372036854774784", v, lo, hi), NumberError::none);
  EXPECT_EQ(v, std::int64_t{9223372036854774784});
  // -2^63 is INT64_MIN itself, exact in double: accepted; the next double below is not.
  ASSERT_EQ(parse_whole<std::int64_t>("-9223372036854775808", v, lo, hi), NumberError::none);
  EXPECT_EQ(v, lo);
  EXPECT_EQ(parse_whole<std::int64_t>("-9223372036854777856", v, lo, hi), NumberError::out_of_range);
}

TEST(FuzzRegressions, WholeNumberBoundsOfNarrowAndUnsignedTypes) {
  int i = 0;
  EXPECT_EQ(parse_whole<int>("2147483648", i, std::numeric_limits<int>::min(), std::numeric_limits<int>::max()),
            NumberError::out_of_range);
  ASSERT_EQ(parse_whole<int>("2147483647.0", i, std::numeric_limits<int>::min(), std::numeric_limits<int>::max()),
            NumberError::none);
  EXPECT_EQ(i, std::numeric_limits<int>::max());
  std::uint32_t u = 0;
  EXPECT_EQ(parse_whole<std::uint32_t>("-1", u, 0u, 10u), NumberError::out_of_range);
  EXPECT_EQ(parse_whole<std::uint32_t>("4294967296", u, 0u, std::numeric_limits<std::uint32_t>::max()),
            NumberError::out_of_range);
  // The caller's bounds still apply inside the type's range.
  EXPECT_EQ(parse_whole<int>("8", i, -5, 7), NumberError::out_of_range);
  ASSERT_EQ(parse_whole<int>("-5", i, -5, 7), NumberError::none);
  EXPECT_EQ(i, -5);
}

}  // namespace

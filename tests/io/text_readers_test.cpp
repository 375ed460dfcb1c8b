// The pieces of io/text.hpp that readers outside io/ build on: a TextFile over a stream the
// caller opened, the header read from the first line, a required column, and the rule sets
// for values without a magnitude bound.
#include <gtest/gtest.h>

#include <ctxfuse/io/text.hpp>

#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <string_view>

#include "temp_files.hpp"

namespace {

using namespace ctxfuse::io;
using TextReaders = ctxfuse::test::TempFiles;

TEST(TextStream, LinesOfAStreamWithTheirNumbers) {
  std::istringstream in("a b\r\n\n  c 1.5\nlast");
  TextFile file(in, "block of m.txt");
  EXPECT_EQ(file.name(), "block of m.txt");
  std::string_view line;
  ASSERT_TRUE(file.next(line));
  EXPECT_EQ(line, "a b");  // CR removed
  EXPECT_EQ(file.line_number(), 1u);
  Fields f(file.name());
  ASSERT_TRUE(next_fields(file, f, Separator::whitespace));  // the blank line 2 is skipped
  EXPECT_EQ(f.line(), 3u);
  ASSERT_EQ(f.size(), 2u);
  EXPECT_EQ(f[0], "c");
  EXPECT_EQ(f.real(1), 1.5);
  EXPECT_PARSE_ERROR(f.real(0), "block of m.txt:3:1", "'c' is not a number");
  ASSERT_TRUE(file.next(line));
  EXPECT_EQ(line, "last");
  EXPECT_FALSE(file.ended_by_newline());
  EXPECT_FALSE(file.next(line));
  EXPECT_PARSE_ERROR(file.fail("too short"), "block of m.txt:4: ", "too short");
}

TEST(TextStream, AnEmptyStreamHasNoLines) {
  std::istringstream in("");
  TextFile file(in, "empty");
  std::string_view line;
  EXPECT_FALSE(file.next(line));
  EXPECT_EQ(file.line_number(), 0u);
}

TEST_F(TextReaders, HeaderFromTheFirstLineAndRequiredColumns) {
  const auto p = write("h.csv", "time_s, sat_id ,cn0\r\n1,G01,40\n");
  TextFile file(p);
  const Header header = read_header(file, Separator::comma);
  ASSERT_EQ(header.size(), 3u);
  EXPECT_EQ(header.name(1), "sat_id");  // trimmed
  EXPECT_EQ(header.name(2), "cn0");     // CR removed
  EXPECT_EQ(require_column(file, header, "cn0"), 2u);
  EXPECT_PARSE_ERROR(require_column(file, header, "pdop"), "h.csv:1: ", "header has no column 'pdop'");
  TextFile empty(write("e.csv", ""));
  // Line 0, the file as a whole: no line number in the message.
  EXPECT_PARSE_ERROR(read_header(empty, Separator::comma), "e.csv: ", "empty file (no header)");
}

TEST(TextRules, WithoutAMagnitudeBound) {
  double v = 0.0;
  EXPECT_EQ(parse_real("1e300", v), NumberError::too_large);  // the default bound
  EXPECT_EQ(parse_real("1e300", v, kAnyFinite), NumberError::none);
  EXPECT_EQ(v, 1e300);
  EXPECT_EQ(parse_real("-1.7976931348623157e308", v, kAnyFinite), NumberError::none);
  EXPECT_EQ(v, -std::numeric_limits<double>::max());
  EXPECT_EQ(parse_real("inf", v, kAnyFinite), NumberError::non_finite);
  EXPECT_EQ(parse_real("nan", v, kAnyFinite), NumberError::non_finite);
  EXPECT_EQ(parse_real("1e400", v, kAnyFinite), NumberError::too_large);  // not a double
  EXPECT_EQ(parse_real("-inf", v, kAnyReal), NumberError::none);
  EXPECT_TRUE(std::isinf(v) && v < 0.0);
  EXPECT_EQ(parse_real("nan", v, kAnyReal), NumberError::none);
  EXPECT_TRUE(std::isnan(v));
  EXPECT_EQ(parse_real("1e300", v, kAnyReal), NumberError::none);
  EXPECT_EQ(parse_real("1e300x", v, kAnyReal), NumberError::trailing_characters);
}

}  // namespace

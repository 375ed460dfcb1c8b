// The shared splitter and number parser: field splitting, every number error, and the
// file:line:column location of the exceptions.
#include <gtest/gtest.h>

#include <ctxfuse/io/text.hpp>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "temp_files.hpp"

namespace {

using namespace ctxfuse::io;
using Text = ctxfuse::test::TempFiles;

TEST(Split, CommaKeepsEmptyFieldsAndTrims) {
  const auto f = split_fields(" a ,\tb,,c \r", Separator::comma);
  ASSERT_EQ(f.size(), 4u);
  EXPECT_EQ(f[0], "a");
  EXPECT_EQ(f[1], "b");
  EXPECT_EQ(f[2], "");
  EXPECT_EQ(f[3], "c");
  EXPECT_EQ(split_fields("", Separator::comma).size(), 1u);
  EXPECT_EQ(split_fields("x,", Separator::comma).size(), 2u);
}

TEST(Split, WhitespaceRunsAreOneSeparator) {
  const auto f = split_fields("  2025/07/08 19:34:18.499\t 40.5   -105.1 \r", Separator::whitespace);
  ASSERT_EQ(f.size(), 4u);
  EXPECT_EQ(f[0], "2025/07/08");
  EXPECT_EQ(f[1], "19:34:18.499");
  EXPECT_EQ(f[3], "-105.1");
  EXPECT_TRUE(split_fields(" \t ", Separator::whitespace).empty());
}

// A quoted field never carries a NUL, a control byte or a stray UTF-8 byte into a message:
// a NUL would cut an exception's what() short of what the non-throwing form reports.
TEST(Quote, EscapesEveryByteOutsidePrintableAscii) {
  EXPECT_EQ(quote("a b~"), "'a b~'");
  EXPECT_EQ(quote(""), "''");
  EXPECT_EQ(quote(std::string("0\0.5", 4)), "'0\\x00.5'");
  EXPECT_EQ(quote("\t\r\n\x1f\x7f"), "'\\x09\\x0d\\x0a\\x1f\\x7f'");
  EXPECT_EQ(quote("\xc3\xa9"), "'\\xc3\\xa9'");
  EXPECT_EQ(printable(std::string("a\0b", 3)), "a\\x00b");
  for (int b = 0; b < 256; ++b) {
    const std::string q = quote(std::string(1, static_cast<char>(b)));
    const bool printable = b >= 0x20 && b < 0x7f;
    EXPECT_EQ(q.size(), printable ? 3u : 6u) << b;
    for (const char c : q) EXPECT_TRUE(c >= 0x20 && c < 0x7f) << b;
  }
}

TEST(Numbers, RealAcceptsWholeFieldsOnly) {
  double v = 0.0;
  EXPECT_EQ(parse_real(" -12.5e1 ", v), NumberError::none);
  EXPECT_EQ(v, -125.0);
  EXPECT_EQ(parse_real("+0.25", v), NumberError::none);
  EXPECT_EQ(v, 0.25);
  v = 7.0;
  EXPECT_EQ(parse_real("", v), NumberError::empty);
  EXPECT_EQ(parse_real("  ", v), NumberError::empty);
  EXPECT_EQ(parse_real("abc", v), NumberError::not_a_number);
  EXPECT_EQ(parse_real("+-1", v), NumberError::not_a_number);
  EXPECT_EQ(parse_real("1.5x", v), NumberError::trailing_characters);
  EXPECT_EQ(parse_real("1,5", v), NumberError::trailing_characters);
  EXPECT_EQ(parse_real("nan", v), NumberError::non_finite);
  EXPECT_EQ(parse_real("-inf", v), NumberError::non_finite);
  EXPECT_EQ(parse_real("1e999", v), NumberError::too_large);
  EXPECT_EQ(parse_real("2e19", v), NumberError::too_large);
  RealRules small;
  small.max_abs = 100.0;
  EXPECT_EQ(parse_real("100.5", v, small), NumberError::too_large);
  EXPECT_EQ(v, 7.0);  // untouched by every failure
  RealRules inf_ok;
  inf_ok.allow_non_finite = true;
  EXPECT_EQ(parse_real("-inf", v, inf_ok), NumberError::none);
  EXPECT_TRUE(std::isinf(v) && v < 0.0);
}

TEST(Numbers, IntegerAndWholeRanges) {
  int i = 0;
  EXPECT_EQ(parse_integer("42", i, 0, 100), NumberError::none);
  EXPECT_EQ(i, 42);
  EXPECT_EQ(parse_integer("+7", i, 0, 100), NumberError::none);
  EXPECT_EQ(i, 7);
  EXPECT_EQ(parse_integer("101", i, 0, 100), NumberError::out_of_range);
  EXPECT_EQ(parse_integer("-1", i, 0, 100), NumberError::out_of_range);
  EXPECT_EQ(parse_integer("99999999999", i), NumberError::out_of_range);
  EXPECT_EQ(parse_integer("4.0", i), NumberError::trailing_characters);
  EXPECT_EQ(parse_integer("x4", i), NumberError::not_a_number);
  std::int64_t big = 0;
  EXPECT_EQ(parse_integer("1734501485317590607", big), NumberError::none);
  EXPECT_EQ(big, 1734501485317590607LL);
  EXPECT_EQ(parse_whole("21.0000000", i, 0, 255), NumberError::none);
  EXPECT_EQ(i, 21);
  EXPECT_EQ(parse_whole("2.5", i, 0, 255), NumberError::not_whole);
  EXPECT_EQ(parse_whole("256", i, 0, 255), NumberError::out_of_range);
}

TEST_F(Text, FieldsNameFileLineColumnAndHeader) {
  const auto p = write("t.csv", "a,b,c\r\n1,2.5,x\r\n1,2\n1,inf,3\n1,1e300,3\n1,2,3");
  TextFile file(p);
  std::string_view line;
  ASSERT_TRUE(file.next(line));
  EXPECT_EQ(line, "a,b,c");  // CR removed
  const Header header(split_fields(line, Separator::comma));
  Fields f(file.name(), &header);
  ASSERT_TRUE(file.next(line));
  f.split(line, file.line_number(), Separator::comma);
  EXPECT_EQ(f.real(1), 2.5);
  EXPECT_EQ(f.integer<int>(0, 0, 5), 1);
  EXPECT_PARSE_ERROR(f.real(2), "t.csv:2:3: column 'c'", "'x' is not a number");
  EXPECT_PARSE_ERROR(f.integer<int>(0, 2, 5), "t.csv:2:1: column 'a'", "'1' is outside the allowed range [2, 5]");
  EXPECT_PARSE_ERROR(f.real_in(1, 3.0, 4.0), "t.csv:2:2: column 'b'", "outside [3, 4]");
  try {
    f.real(2);
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file(), p.string());
    EXPECT_EQ(e.line(), 2u);
    EXPECT_EQ(e.column(), 3u);
    EXPECT_EQ(e.column_name(), "c");
  }
  ASSERT_TRUE(file.next(line));
  f.split(line, file.line_number(), Separator::comma);
  EXPECT_PARSE_ERROR(f.expect_count(3), "t.csv:3: ", "2 fields, expected 3");
  EXPECT_PARSE_ERROR(f.real(2), "t.csv:3:3: column 'c'", "missing field");
  ASSERT_TRUE(file.next(line));
  f.split(line, file.line_number(), Separator::comma);
  EXPECT_PARSE_ERROR(f.real(1), "t.csv:4:2", "'inf' is not finite");
  ASSERT_TRUE(file.next(line));
  f.split(line, file.line_number(), Separator::comma);
  EXPECT_PARSE_ERROR(f.real(1), "t.csv:5:2", "beyond the magnitude");
  EXPECT_TRUE(file.ended_by_newline());
  ASSERT_TRUE(file.next(line));
  EXPECT_EQ(line, "1,2,3");
  EXPECT_FALSE(file.ended_by_newline());
  EXPECT_FALSE(file.next(line));
}

TEST_F(Text, MissingFileIsAParseErrorNamingIt) {
  EXPECT_PARSE_ERROR(TextFile(dir_ / "absent.csv"), "absent.csv: ", "cannot open file");
}

}  // namespace

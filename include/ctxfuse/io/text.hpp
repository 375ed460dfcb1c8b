// The one field splitter and number parser of the recorded-log readers. Every reader goes
// through it so that a bad value is reported the same way everywhere: file:line:column, the
// column being the 1-based field index and, where the file has a header, the column's name.
//
// - Numbers are parsed with std::from_chars (locale-independent, no silent prefix parse): the
//   whole field must be the number, one leading '+' is allowed, surrounding spaces and tabs
//   are trimmed. Non-finite values are refused unless the caller allows them, and so are
//   magnitudes beyond a caller-set bound (a 1e300 latitude is a corrupt line, not a value).
// - Lines may end in CRLF (logs copied from Windows loggers do); the CR never reaches a field.
// - Two record shapes: comma-separated (empty fields kept, so a column count is exact) and
//   whitespace-separated (runs of blanks are one separator, as in RTKLIB .pos files).
#pragma once

#include <charconv>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <istream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <utility>
#include <vector>

#include "ctxfuse/core/error.hpp"

namespace ctxfuse::io {

/// A reader's complaint about its input. line 0: the file as a whole (cannot open, missing
/// folder, binary layout); column 0: the line as a whole (field count, order of records).
class ParseError : public std::runtime_error {
 public:
  ParseError(std::string file, std::size_t line, std::size_t column, std::string column_name, std::string reason)
      : std::runtime_error(format(file, line, column, column_name, reason)),
        file_(std::move(file)),
        line_(line),
        column_(column),
        column_name_(std::move(column_name)),
        reason_(std::move(reason)) {}

  const std::string& file() const { return file_; }
  std::size_t line() const { return line_; }
  std::size_t column() const { return column_; }
  const std::string& column_name() const { return column_name_; }
  const std::string& reason() const { return reason_; }

 private:
  // Appended piece by piece: g++ 12 warns (-Wrestrict, a false positive) on an inlined
  // `"literal" + std::string&&` chain.
  static std::string format(const std::string& file, std::size_t line, std::size_t column, const std::string& name,
                            const std::string& reason) {
    std::string m = file;
    if (line > 0) m.append(":").append(std::to_string(line));
    if (line > 0 && column > 0) m.append(":").append(std::to_string(column));
    if (!name.empty()) m.append(": column '").append(name).append("'");
    return m.append(": ").append(reason);
  }

  std::string file_;
  std::size_t line_;
  std::size_t column_;
  std::string column_name_;
  std::string reason_;
};

namespace detail {
inline void append_part(std::string& s, std::string_view v) { s.append(v); }
inline void append_part(std::string& s, char c) { s.push_back(c); }
template <class T>
  requires std::is_arithmetic_v<T>
void append_part(std::string& s, T v) {
  if constexpr (std::is_floating_point_v<T>) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);  // shortest round-trip form
    s.append(buf, r.ptr);
  } else {
    s.append(std::to_string(v));
  }
}
}  // namespace detail

/// Concatenates text and numbers into a message. Built by appending: g++ 12 warns
/// (-Wrestrict, a false positive) on inlined `"literal" + std::string&&` chains.
template <class... Parts>
std::string cat(const Parts&... parts) {
  std::string s;
  (detail::append_part(s, parts), ...);
  return s;
}

/// The text with every byte outside printable ASCII written as \xNN, for a message that shows
/// what a file holds: a message never carries a NUL, a control character or a broken UTF-8
/// sequence from a malformed file into a log (a NUL would also cut an exception's what()).
inline std::string printable(std::string_view s) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(s.size());
  for (const char c : s) {
    const auto b = static_cast<unsigned char>(c);
    if (b >= 0x20 && b < 0x7f) {
      out += c;
    } else {
      out += "\\x";
      out += kHex[b >> 4];
      out += kHex[b & 0xf];
    }
  }
  return out;
}

/// 'text', printable, for messages that quote a field.
inline std::string quote(std::string_view s) { return cat('\'', printable(s), '\''); }

enum class Separator { comma, whitespace };

inline constexpr bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

inline std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

/// Splits `line` into `out` (cleared first; reused across lines so a reader does not allocate
/// per line). Each field is trimmed. With commas, "a,,b" has three fields and "" has one.
inline void split_fields(std::string_view line, Separator sep, std::vector<std::string_view>& out) {
  out.clear();
  if (sep == Separator::comma) {
    std::size_t start = 0;
    while (true) {
      const auto comma = line.find(',', start);
      out.push_back(trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
      if (comma == std::string_view::npos) return;
      start = comma + 1;
    }
  }
  std::size_t i = 0;
  while (true) {
    while (i < line.size() && is_blank(line[i])) ++i;
    if (i == line.size()) return;
    const std::size_t start = i;
    while (i < line.size() && !is_blank(line[i])) ++i;
    out.push_back(line.substr(start, i - start));
  }
}

inline std::vector<std::string_view> split_fields(std::string_view line, Separator sep) {
  std::vector<std::string_view> out;
  split_fields(line, sep, out);
  return out;
}

enum class NumberError { none, empty, not_a_number, trailing_characters, non_finite, too_large, out_of_range, not_whole };

inline std::string describe(NumberError e, std::string_view field) {
  const std::string quoted = quote(field);
  switch (e) {
    case NumberError::none: return "no error";
    case NumberError::empty: return "empty field, expected a number";
    case NumberError::not_a_number: return quoted + " is not a number";
    case NumberError::trailing_characters: return quoted + " has characters after the number";
    case NumberError::non_finite: return quoted + " is not finite";
    case NumberError::too_large: return quoted + " is beyond the magnitude this column accepts";
    case NumberError::out_of_range: return quoted + " is outside the allowed range";
    case NumberError::not_whole: return quoted + " is not a whole number";
  }
  return quoted + ": unknown number error";
}

struct RealRules {
  bool allow_non_finite = false;
  /// Finite values with a larger magnitude are refused (the default admits nanosecond stamps).
  double max_abs = 1e19;
};

/// Every finite value, however large: for columns whose writer sets no bound (features,
/// model parameters).
inline constexpr RealRules kAnyFinite{false, std::numeric_limits<double>::max()};
/// Every value, the inf/-inf/nan spellings included, however large.
inline constexpr RealRules kAnyReal{true, std::numeric_limits<double>::max()};

namespace detail {
// from_chars has no '+' (it follows strtod's C-locale grammar minus the sign); loggers write one.
inline std::string_view drop_plus(std::string_view s) {
  if (s.size() > 1 && s.front() == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
  return s;
}
}  // namespace detail

inline NumberError parse_real(std::string_view field, double& out, RealRules rules = {}) {
  std::string_view s = detail::drop_plus(trim(field));
  if (s.empty()) return NumberError::empty;
  double v = 0.0;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec == std::errc::result_out_of_range) return NumberError::too_large;  // also denormal underflow
  if (ec != std::errc{}) return NumberError::not_a_number;
  if (p != s.data() + s.size()) return NumberError::trailing_characters;
  if (!std::isfinite(v)) {
    if (!rules.allow_non_finite) return NumberError::non_finite;
  } else if (std::abs(v) > rules.max_abs) {
    return NumberError::too_large;
  }
  out = v;
  return NumberError::none;
}

template <class Int>
NumberError parse_integer(std::string_view field, Int& out, Int lo = std::numeric_limits<Int>::min(),
                          Int hi = std::numeric_limits<Int>::max()) {
  std::string_view s = detail::drop_plus(trim(field));
  if (s.empty()) return NumberError::empty;
  Int v{};
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec == std::errc::result_out_of_range) return NumberError::out_of_range;
  if (ec != std::errc{}) return NumberError::not_a_number;
  if (p != s.data() + s.size()) return NumberError::trailing_characters;
  if (v < lo || v > hi) return NumberError::out_of_range;
  out = v;
  return NumberError::none;
}

/// An integer that some writers print as a decimal ("1.0000000"): any exact whole value.
template <class Int>
NumberError parse_whole(std::string_view field, Int& out, Int lo, Int hi) {
  double v = 0.0;
  if (const auto e = parse_real(field, v); e != NumberError::none) return e;
  if (v != std::floor(v)) return NumberError::not_whole;
  // Inside Int's range before converting: comparing with double(hi) is not enough, since
  // double(INT64_MAX) rounds up to 2^63, which passes `v > hi` and then does not fit (the
  // conversion is undefined behaviour; the fuzz target of io/text.hpp found it). The
  // exclusive bound 2^digits and the bound min() are powers of two (or 0), exact in double.
  constexpr double type_hi = 2.0 * static_cast<double>(std::numeric_limits<Int>::max() / 2 + 1);
  if (!(v >= static_cast<double>(std::numeric_limits<Int>::min()) && v < type_hi)) return NumberError::out_of_range;
  const Int w = static_cast<Int>(v);
  if (w < lo || w > hi) return NumberError::out_of_range;
  out = w;
  return NumberError::none;
}

/// Column names of a file's header, for lookup and for naming columns in errors.
class Header {
 public:
  Header() = default;
  explicit Header(std::vector<std::string> names) : names_(std::move(names)) {}
  explicit Header(const std::vector<std::string_view>& fields) : names_(fields.begin(), fields.end()) {}

  std::size_t size() const { return names_.size(); }
  const std::string& name(std::size_t i) const { return names_[i]; }
  /// Name of the 0-based field i, empty past the header's end.
  std::string name_or_empty(std::size_t i) const { return i < names_.size() ? names_[i] : std::string(); }
  std::optional<std::size_t> find(std::string_view name) const {
    for (std::size_t i = 0; i < names_.size(); ++i)
      if (names_[i] == name) return i;
    return std::nullopt;
  }

 private:
  std::vector<std::string> names_;
};

/// A text file read line by line, knowing where it is for error messages.
class TextFile {
 public:
  explicit TextFile(const std::filesystem::path& path) : name_(path.string()), file_(path, std::ios::binary) {
    if (!file_) ctxfuse::detail::raise(ParseError(name_, 0, 0, "", "cannot open file"));
  }
  /// The lines of a stream the caller has opened (text in memory, a block of a larger file),
  /// called `name` in errors and counted from 1. The stream must outlive this reader.
  TextFile(std::istream& in, std::string name) : name_(std::move(name)), stream_(&in) {}

  /// Next line without its line ending; false at the end of the file. `ended_by_newline`
  /// tells whether it had one (a logger's cut-off last line does not).
  bool next(std::string_view& line) {
    std::istream& in = stream_ ? *stream_ : file_;
    if (!std::getline(in, buffer_)) return false;
    ++line_number_;
    ended_by_newline_ = !in.eof();
    if (!buffer_.empty() && buffer_.back() == '\r') buffer_.pop_back();
    line = buffer_;
    return true;
  }
  bool ended_by_newline() const { return ended_by_newline_; }
  std::size_t line_number() const { return line_number_; }
  const std::string& name() const { return name_; }

  [[noreturn]] void fail(std::string reason) const { ctxfuse::detail::raise(ParseError(name_, line_number_, 0, "", std::move(reason))); }

 private:
  std::string name_;
  std::ifstream file_;               // read when opened from a path
  std::istream* stream_ = nullptr;  // read instead when given
  std::string buffer_;
  std::size_t line_number_ = 0;
  bool ended_by_newline_ = true;
};

/// The header of a file that has one on its first line; a ParseError when the file is empty.
inline Header read_header(TextFile& file, Separator sep) {
  std::string_view line;
  if (!file.next(line)) file.fail("empty file (no header)");
  return Header(split_fields(line, sep));
}

/// Index of a column the reader needs. A header without it fails at the file's current line
/// (the header's, when called right after reading it).
inline std::size_t require_column(const TextFile& file, const Header& header, std::string_view name) {
  const auto i = header.find(name);
  if (!i) file.fail(cat("header has no column ", quote(name)));
  return *i;
}

/// The fields of one line with their location: typed accessors that throw ParseError.
class Fields {
 public:
  Fields(std::string file, const Header* header = nullptr) : file_(std::move(file)), header_(header) {}

  void split(std::string_view line, std::size_t line_number, Separator sep) {
    line_ = line_number;
    split_fields(line, sep, fields_);
  }

  std::size_t size() const { return fields_.size(); }
  std::string_view operator[](std::size_t i) const { return fields_[i]; }
  std::size_t line() const { return line_; }
  const std::string& file() const { return file_; }

  void expect_count(std::size_t n) const {
    if (fields_.size() != n)
      fail_line(cat(fields_.size(), " fields, expected ", n, header_ ? " (as in the header)" : ""));
  }
  void expect_at_least(std::size_t n) const {
    if (fields_.size() < n) fail_line(cat(fields_.size(), " fields, expected at least ", n));
  }

  double real(std::size_t i, RealRules rules = {}) const {
    double v = 0.0;
    check(i, parse_real(field(i), v, rules));
    return v;
  }
  /// A finite real inside [lo, hi].
  double real_in(std::size_t i, double lo, double hi, RealRules rules = {}) const {
    const double v = real(i, rules);
    if (!std::isfinite(v)) return v;  // only when the rules allow it
    if (!(v >= lo && v <= hi))
      fail(i, cat(quote(fields_[i]), " outside [", lo, ", ", hi, "]"));
    return v;
  }
  template <class Int>
  Int integer(std::size_t i, Int lo, Int hi) const {
    Int v{};
    check(i, parse_integer(field(i), v, lo, hi), lo, hi);
    return v;
  }
  template <class Int>
  Int whole(std::size_t i, Int lo, Int hi) const {
    Int v{};
    check(i, parse_whole(field(i), v, lo, hi), lo, hi);
    return v;
  }

  /// Throws naming field i (0-based here, 1-based in the message) and its header name.
  [[noreturn]] void fail(std::size_t i, std::string reason) const {
    ctxfuse::detail::raise(ParseError(file_, line_, i + 1, header_ ? header_->name_or_empty(i) : std::string(), std::move(reason)));
  }
  [[noreturn]] void fail_line(std::string reason) const { ctxfuse::detail::raise(ParseError(file_, line_, 0, "", std::move(reason))); }

 private:
  std::string_view field(std::size_t i) const {
    if (i >= fields_.size()) fail(i, cat("missing field (the line has ", fields_.size(), ")"));
    return fields_[i];
  }
  template <class T = int>
  void check(std::size_t i, NumberError e, T lo = 0, T hi = 0) const {
    if (e == NumberError::none) return;
    std::string m = describe(e, fields_[i]);
    if (e == NumberError::out_of_range && lo != hi) m += cat(" [", lo, ", ", hi, "]");
    fail(i, std::move(m));
  }

  std::string file_;
  const Header* header_;
  std::vector<std::string_view> fields_;
  std::size_t line_ = 0;
};

/// Splits the next non-blank line of `file` into `f`; false at the end of the file.
inline bool next_fields(TextFile& file, Fields& f, Separator sep) {
  std::string_view line;
  while (file.next(line))
    if (!trim(line).empty()) {
      f.split(line, file.line_number(), sep);
      return true;
    }
  return false;
}

}  // namespace ctxfuse::io

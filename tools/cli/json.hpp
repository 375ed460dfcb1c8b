// A small ordered JSON document for the CLI's --json outputs: objects keep insertion order,
// numbers are printed with enough digits to round-trip, non-finite numbers become null.
#pragma once

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <ostream>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace ctxfuse::cli {

class Json {
 public:
  using Object = std::vector<std::pair<std::string, Json>>;
  using Array = std::vector<Json>;

  Json() : value_(Object{}) {}
  Json(double v) : value_(v) {}                       // NOLINT(google-explicit-constructor)
  Json(int v) : value_(static_cast<double>(v)) {}     // NOLINT
  Json(long v) : value_(static_cast<double>(v)) {}    // NOLINT
  Json(long long v) : value_(static_cast<double>(v)) {}  // NOLINT
  Json(unsigned long v) : value_(static_cast<double>(v)) {}  // NOLINT
  Json(bool v) : value_(v) {}                         // NOLINT
  Json(std::string v) : value_(std::move(v)) {}       // NOLINT
  Json(const char* v) : value_(std::string(v)) {}     // NOLINT
  Json(Array a) : value_(std::move(a)) {}             // NOLINT

  static Json array() { return Json(Array{}); }

  /// Member access on an object; creates the member (as an empty object) when missing.
  Json& operator[](std::string_view key) {
    auto& obj = as_object();
    for (auto& [k, v] : obj)
      if (k == key) return v;
    obj.emplace_back(std::string(key), Json{});
    return obj.back().second;
  }

  /// Dotted path, e.g. set("region_imm.mean_error_m.imm.overall", 1.39).
  Json& set(std::string_view dotted, Json v) {
    Json* node = this;
    while (true) {
      auto dot = dotted.find('.');
      if (dot == std::string_view::npos) {
        (*node)[dotted] = std::move(v);
        return (*node)[dotted];
      }
      node = &(*node)[dotted.substr(0, dot)];
      dotted.remove_prefix(dot + 1);
    }
  }

  /// Looks a dotted path up without creating anything; nullptr when absent.
  const Json* find(std::string_view dotted) const {
    const Json* node = this;
    while (node) {
      auto dot = dotted.find('.');
      auto key = dotted.substr(0, dot);
      const auto* obj = std::get_if<Object>(&node->value_);
      if (!obj) return nullptr;
      const Json* next = nullptr;
      for (const auto& [k, v] : *obj)
        if (k == key) next = &v;
      node = next;
      if (dot == std::string_view::npos) return node;
      dotted.remove_prefix(dot + 1);
    }
    return nullptr;
  }

  /// A number, built in place (g++ 12 reports a moved temporary's variant as maybe
  /// uninitialized, -Wmaybe-uninitialized, a false positive).
  template <class T>
    requires(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>)
  void push_back(T x) {
    if (!std::holds_alternative<Array>(value_)) value_ = Array{};
    std::get<Array>(value_).emplace_back(static_cast<double>(x));
  }
  void push_back(Json v) {
    if (!std::holds_alternative<Array>(value_)) value_ = Array{};
    std::get<Array>(value_).push_back(std::move(v));
  }

  bool is_object() const { return std::holds_alternative<Object>(value_); }
  bool is_number() const { return std::holds_alternative<double>(value_); }
  double number() const { return std::get<double>(value_); }
  const Object& object() const { return std::get<Object>(value_); }

  void dump(std::ostream& os, int indent = 2, int depth = 0) const {
    std::visit([&](const auto& v) { write(os, v, indent, depth); }, value_);
  }
  std::string str(int indent = 2) const {
    std::string s;
    struct StrBuf : std::streambuf {
      std::string* s;
      int_type overflow(int_type c) override {
        if (c != traits_type::eof()) s->push_back(static_cast<char>(c));
        return c;
      }
    } buf;
    buf.s = &s;
    std::ostream os(&buf);
    dump(os, indent);
    return s;
  }

 private:
  Object& as_object() {
    if (!std::holds_alternative<Object>(value_)) value_ = Object{};
    return std::get<Object>(value_);
  }
  static void newline(std::ostream& os, int indent, int depth) {
    if (indent <= 0) return;
    os << '\n' << std::string(static_cast<std::size_t>(indent * depth), ' ');
  }
  static void write(std::ostream& os, double v, int, int) {
    if (!std::isfinite(v)) {
      os << "null";
      return;
    }
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    os << buf;
  }
  static void write(std::ostream& os, bool v, int, int) { os << (v ? "true" : "false"); }
  static void write(std::ostream& os, const std::string& v, int, int) {
    os << '"';
    for (char c : v) {
      switch (c) {
        case '"': os << "\\\""; break;
        case '\\': os << "\\\\"; break;
        case '\n': os << "\\n"; break;
        case '\t': os << "\\t"; break;
        default:
          if (static_cast<unsigned char>(c) < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", c);
            os << buf;
          } else {
            os << c;
          }
      }
    }
    os << '"';
  }
  static void write(std::ostream& os, const Array& a, int indent, int depth) {
    os << '[';
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (i) os << ',';
      newline(os, indent, depth + 1);
      a[i].dump(os, indent, depth + 1);
    }
    if (!a.empty()) newline(os, indent, depth);
    os << ']';
  }
  static void write(std::ostream& os, const Object& o, int indent, int depth) {
    os << '{';
    for (std::size_t i = 0; i < o.size(); ++i) {
      if (i) os << ',';
      newline(os, indent, depth + 1);
      write(os, o[i].first, indent, depth + 1);
      os << (indent > 0 ? ": " : ":");
      o[i].second.dump(os, indent, depth + 1);
    }
    if (!o.empty()) newline(os, indent, depth);
    os << '}';
  }

  std::variant<Object, Array, double, bool, std::string> value_;
};

/// Writes `doc` and a newline to `path`; false, with "ctxfuse <command>: cannot write <path>"
/// on `err`, when the file cannot be written.
inline bool write_json_file(const Json& doc, const std::string& path, std::string_view command, std::ostream& err) {
  std::ofstream os(path);
  doc.dump(os);
  os << '\n';
  if (!os.flush()) {
    err << "ctxfuse " << command << ": cannot write " << path << '\n';
    return false;
  }
  return true;
}

}  // namespace ctxfuse::cli

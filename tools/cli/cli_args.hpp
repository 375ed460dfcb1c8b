// Minimal "--flag value" parsing shared by the demo/sim/run/plot commands: every flag is
// declared, unknown flags and missing or malformed values are usage errors naming the flag.
#pragma once

#include <charconv>
#include <cstdint>
#include <map>
#include <optional>
#include <ostream>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "cli/registry.hpp"

namespace ctxfuse::cli {

class FlagParser {
 public:
  FlagParser(std::string_view command, std::set<std::string, std::less<>> flags_with_value)
      : command_(command), flags_(std::move(flags_with_value)) {}

  /// Fills flags and positionals; on error prints to err and returns false.
  bool parse(Args args, std::ostream& err) {
    for (std::size_t i = 0; i < args.size(); ++i) {
      const std::string_view a = args[i];
      if (a.starts_with("--")) {
        if (!flags_.count(a)) {
          err << "ctxfuse " << command_ << ": unknown option '" << a << "'\n";
          return false;
        }
        if (i + 1 >= args.size()) {
          err << "ctxfuse " << command_ << ": option '" << a << "' needs a value\n";
          return false;
        }
        values_[std::string(a)] = std::string(args[++i]);
      } else {
        positionals_.emplace_back(a);
      }
    }
    return true;
  }
  std::optional<std::string> get(std::string_view flag) const {
    auto it = values_.find(std::string(flag));
    if (it == values_.end()) return std::nullopt;
    return it->second;
  }
  /// Unsigned integer flag; on a malformed value prints to err and returns nullopt via ok=false.
  bool get_u64(std::string_view flag, std::uint64_t& out, std::ostream& err) const {
    auto v = get(flag);
    if (!v) return true;
    std::uint64_t x = 0;
    const auto res = std::from_chars(v->data(), v->data() + v->size(), x);
    if (v->empty() || res.ec != std::errc() || res.ptr != v->data() + v->size()) {
      err << "ctxfuse " << command_ << ": " << flag << " expects a non-negative integer, got '" << *v << "'\n";
      return false;
    }
    out = x;
    return true;
  }
  bool get_double(std::string_view flag, double& out, std::ostream& err) const {
    auto v = get(flag);
    if (!v) return true;
    double x = 0;
    const auto res = std::from_chars(v->data(), v->data() + v->size(), x);
    if (v->empty() || res.ec != std::errc() || res.ptr != v->data() + v->size() || !(x == x)) {
      err << "ctxfuse " << command_ << ": " << flag << " expects a number, got '" << *v << "'\n";
      return false;
    }
    out = x;
    return true;
  }
  const std::vector<std::string>& positionals() const { return positionals_; }

 private:
  std::string command_;
  std::set<std::string, std::less<>> flags_;
  std::map<std::string, std::string> values_;
  std::vector<std::string> positionals_;
};

inline bool wants_help(Args args) {
  for (auto a : args)
    if (a == "--help" || a == "-h") return true;
  return false;
}

}  // namespace ctxfuse::cli

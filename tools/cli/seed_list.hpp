// The seed lists of the commands that run many simulated drives: "1-5", "1,3,7", "2-4,9".
#pragma once

#include <charconv>
#include <cstdint>
#include <limits>
#include <ostream>
#include <set>
#include <string_view>
#include <vector>

namespace ctxfuse::cli {

/// "1-5", "1,3,7", "2-4,9": ascending or not, each seed at most once.
inline bool parse_seeds(std::string_view text, std::vector<std::uint64_t>& seeds, std::ostream& err) {
  // Training and validation use seed + 101..103 and seed + 202.
  constexpr std::uint64_t kMaxSeed = std::numeric_limits<std::uint32_t>::max();
  constexpr std::size_t kMaxCount = 10000;
  auto number = [&](std::string_view s, std::uint64_t& v) {
    const auto res = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || res.ec != std::errc() || res.ptr != s.data() + s.size() || v > kMaxSeed) {
      err << "ctxfuse region-study: --seeds: '" << s << "' is not a seed (an integer 0.." << kMaxSeed << ")\n";
      return false;
    }
    return true;
  };
  seeds.clear();
  std::set<std::uint64_t> seen;
  if (text.empty()) {
    err << "ctxfuse region-study: --seeds: empty list\n";
    return false;
  }
  while (true) {
    const auto comma = text.find(',');
    const std::string_view item = text.substr(0, comma);
    std::uint64_t lo = 0, hi = 0;
    const auto dash = item.find('-');
    if (dash == std::string_view::npos) {
      if (!number(item, lo)) return false;
      hi = lo;
    } else if (!number(item.substr(0, dash), lo) || !number(item.substr(dash + 1), hi)) {
      return false;
    } else if (hi < lo) {
      err << "ctxfuse region-study: --seeds: range '" << item << "' runs backwards\n";
      return false;
    }
    if (hi - lo >= kMaxCount || seeds.size() + (hi - lo + 1) > kMaxCount) {
      err << "ctxfuse region-study: --seeds: more than " << kMaxCount << " seeds\n";
      return false;
    }
    for (std::uint64_t s = lo; s <= hi; ++s) {
      if (!seen.insert(s).second) {
        err << "ctxfuse region-study: --seeds: seed " << s << " listed twice\n";
        return false;
      }
      seeds.push_back(s);
    }
    if (comma == std::string_view::npos) return true;
    text.remove_prefix(comma + 1);
  }
}

}  // namespace ctxfuse::cli

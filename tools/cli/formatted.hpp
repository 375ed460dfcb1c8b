// printf-style formatting into a std::string, for the CLI's tables ("C" locale digits, the same
// bytes whatever the compiler); a line longer than the buffer is cut, never overrun.
#pragma once

#include <cstdio>
#include <string>

namespace ctxfuse::cli {

inline std::string formatted(const char* f, auto... v) {
  char buf[512];
  std::snprintf(buf, sizeof buf, f, v...);
  return buf;
}

}  // namespace ctxfuse::cli

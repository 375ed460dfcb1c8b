// What every fuzz target shares: the readers under test take file paths, so each input is
// written to a file in one scratch folder per process (created on first use, removed at
// exit), and inputs that carry several files are split by a 2-byte length prefix.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <utility>

namespace ctxfuse_fuzz {

/// A folder of this process, emptied by the destructor (libFuzzer's -fork runs several).
class Scratch {
 public:
  Scratch() {
    const char* base = std::getenv("TMPDIR");
    dir_ = std::filesystem::path(base && *base ? base : "/tmp") / ("ctxfuse-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
  }
  ~Scratch() {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  const std::filesystem::path& dir() const { return dir_; }
  /// Writes bytes to dir/name (replacing it) and returns the path.
  std::filesystem::path write(const std::string& name, std::string_view bytes) const {
    const auto p = dir_ / name;
    std::ofstream os(p, std::ios::binary | std::ios::trunc);
    os.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!os) {
      std::fprintf(stderr, "fuzz: cannot write %s\n", p.c_str());
      std::abort();  // a broken harness must not look like a clean run
    }
    return p;
  }

 private:
  std::filesystem::path dir_;
};

inline Scratch& scratch() {
  static Scratch s;
  return s;
}

/// The input as two parts: the first 2 bytes (little-endian) give the first part's length,
/// clipped to what is there; the second part is the rest. Inputs shorter than 2 bytes are
/// all second part. A length prefix, not a separator, so that either part can hold any byte.
inline std::pair<std::string_view, std::string_view> split2(const std::uint8_t* data, std::size_t size) {
  const char* p = reinterpret_cast<const char*>(data);
  if (size < 2) return {std::string_view(), std::string_view(p, size)};
  std::size_t n = static_cast<std::size_t>(data[0]) | (static_cast<std::size_t>(data[1]) << 8);
  if (n > size - 2) n = size - 2;
  return {std::string_view(p + 2, n), std::string_view(p + 2 + n, size - 2 - n)};
}

/// Stops the run with a message: a broken invariant is a finding, like a sanitizer report.
[[noreturn]] inline void fail(const char* what) {
  std::fprintf(stderr, "fuzz invariant broken: %s\n", what);
  std::abort();
}

}  // namespace ctxfuse_fuzz

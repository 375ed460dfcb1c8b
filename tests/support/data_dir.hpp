// Locating ../shared/data from tests. One setting: the CTXFUSE_DATA_DIR environment variable
// (ctest passes the CMake cache entry of the same name). When the folder or a file is absent
// the test is skipped with a message, except under CI=true, where absence is a failure.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace ctxfuse::test {

inline bool running_in_ci() {
  const char* ci = std::getenv("CI");
  return ci != nullptr && std::string(ci) == "true";
}

inline std::filesystem::path data_dir() {
  const char* env = std::getenv("CTXFUSE_DATA_DIR");
  return env ? std::filesystem::path(env) : std::filesystem::path("../shared/data");
}

}  // namespace ctxfuse::test

/// Declares `var` as data_dir()/relative; skips (or fails under CI=true) when it is absent.
/// (The parameter must not be called `path`: it would also replace the `path` of
/// std::filesystem::path inside the expansion.)
#define CTXFUSE_REQUIRE_DATA(var, relative)                                                   \
  const std::filesystem::path var = ::ctxfuse::test::data_dir() / (relative);                \
  do {                                                                                        \
    if (!std::filesystem::exists(var)) {                                                      \
      if (::ctxfuse::test::running_in_ci()) {                                                 \
        FAIL() << "shared data missing under CI=true: " << var                               \
               << " (set CTXFUSE_DATA_DIR to the shared/data folder)";                       \
      } else {                                                                                \
        GTEST_SKIP() << "shared data not found: " << var                                     \
                     << " (set CTXFUSE_DATA_DIR to the shared/data folder to run this test)"; \
      }                                                                                       \
    }                                                                                         \
  } while (0)

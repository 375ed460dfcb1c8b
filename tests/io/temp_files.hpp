// Small files written by the reader tests: one fresh folder per test, removed afterwards, and
// a check that a call throws ParseError with the expected location and message.
#pragma once

#include <gtest/gtest.h>

#include <ctxfuse/io/text.hpp>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace ctxfuse::test {

class TempFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           ("ctxfuse_io_" + std::string(info->test_suite_name()) + "_" + info->name() + "_" +
            std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::filesystem::path write(const std::string& name, const std::string& text) const {
    const auto p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }
  std::filesystem::path dir_;
};

/// The whole file, bytes as they are.
inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// The number of lines of `text` that end, newline included, at or before byte `cut`.
inline std::size_t whole_lines(const std::string& text, std::size_t cut) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < cut; ++i) n += text[i] == '\n';
  return n;
}

}  // namespace ctxfuse::test

/// Runs `call`, which must throw io::ParseError whose what() contains `where` (e.g.
/// "a.pos:3:5") and `reason`.
#define EXPECT_PARSE_ERROR(call, where, reason)                                             \
  do {                                                                                      \
    try {                                                                                   \
      (void)(call);                                                                         \
      ADD_FAILURE() << "expected ParseError from " #call;                                   \
    } catch (const ::ctxfuse::io::ParseError& e_) {                                         \
      const std::string w_ = e_.what();                                                     \
      EXPECT_NE(w_.find(where), std::string::npos) << "location '" << (where) << "' in: " << w_; \
      EXPECT_NE(w_.find(reason), std::string::npos) << "reason '" << (reason) << "' in: " << w_; \
    }                                                                                       \
  } while (0)

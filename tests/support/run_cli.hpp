// Running the built `ctxfuse` executable from a test: its path comes from the build
// (CTXFUSE_CLI_PATH, set with add_dependencies in tests/cli/CMakeLists.txt).
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#ifndef CTXFUSE_CLI_PATH
#error "CTXFUSE_CLI_PATH must name the ctxfuse executable (tests/cli/CMakeLists.txt)"
#endif

namespace ctxfuse::test {

struct CliRun {
  int code = -1;    // exit status; 128 + signal when killed
  std::string out;  // stdout, and stderr too with Stderr::merged
  std::string err;  // stderr with Stderr::separate
};

enum class Stderr { merged, separate };

/// An empty scratch folder for one test, named by `name` and the process id: ctest runs test
/// cases in parallel processes (and several build trees may test at once), so a fixed name
/// would let one test rewrite another's files.
inline std::filesystem::path scratch_dir(const std::string& name) {
  namespace fs = std::filesystem;
  const fs::path p = fs::temp_directory_path() / ("ctxfuse_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

/// Runs `ctxfuse <args>` through the shell (args are pasted in as they are).
inline CliRun run_cli(const std::string& args, Stderr mode = Stderr::merged) {
  namespace fs = std::filesystem;
  const fs::path err_file = fs::temp_directory_path() / ("ctxfuse_cli_err_" + std::to_string(::getpid()));
  std::string cmd = std::string("\"") + CTXFUSE_CLI_PATH + "\" " + args;
  cmd += mode == Stderr::merged ? std::string(" 2>&1") : " 2>\"" + err_file.string() + "\"";
  CliRun r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, pipe)) > 0) r.out.append(buf, n);
  const int status = pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  if (mode == Stderr::separate) {
    std::ifstream e(err_file);
    std::stringstream s;
    s << e.rdbuf();
    r.err = s.str();
    fs::remove(err_file);
  }
  return r;
}

}  // namespace ctxfuse::test

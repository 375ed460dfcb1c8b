// Logs in, truth out, end to end: `ctxfuse sim` writes the demo's test drive and its training
// and validation drives as logs, `ctxfuse run region-imm` trains the recogniser on the
// training logs and runs the pipeline on the test log, and every number it reports must be
// the demo's `region_imm` number for that seed (to a relative 1e-9; the logs round-trip
// exactly, so they are in fact equal). A recogniser saved by one run and loaded by another
// gives the same numbers again.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "support/run_cli.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

// Named, not anonymous: the area's sources share one unity build (tests/CMakeLists.txt).
namespace run_region_imm_cli {

ctxfuse::test::CliRun run(const std::string& args) { return ctxfuse::test::run_cli(args, ctxfuse::test::Stderr::separate); }

fs::path scratch(const std::string& name) {
  const auto p = fs::temp_directory_path() / ("ctxfuse_run_region_" + std::to_string(::getpid())) / name;
  fs::create_directories(p);
  return p;
}

json read_json(const fs::path& p) {
  std::ifstream in(p);
  return json::parse(in);
}

/// Every number (and flag) of `expected` must be in `actual` at the same path, equal to a
/// relative 1e-9; returns how many were compared.
int compare(const json& expected, const json& actual, const std::string& path) {
  int n = 0;
  if (expected.is_object()) {
    for (auto it = expected.begin(); it != expected.end(); ++it) {
      EXPECT_TRUE(actual.contains(it.key())) << path << "." << it.key() << " missing";
      if (actual.contains(it.key())) n += compare(*it, actual[it.key()], path + "." + it.key());
    }
  } else if (expected.is_number()) {
    const double e = expected.get<double>(), a = actual.is_number() ? actual.get<double>() : std::nan("");
    EXPECT_LE(std::abs(a - e), 1e-9 * std::max(1.0, std::abs(e))) << path << ": run " << a << ", demo " << e;
    ++n;
  } else if (expected.is_null()) {  // a NaN in the demo (no such epoch)
    EXPECT_TRUE(actual.is_null()) << path;
    ++n;
  } else {
    EXPECT_EQ(expected, actual) << path;
    ++n;
  }
  return n;
}

constexpr int kSeed = 2;

TEST(RunRegionImm, LogsOfTheDemoDrivesGiveTheDemosNumbers) {
  const fs::path root = scratch("logs");
  auto sim = [&](int seed) {
    const fs::path dir = root / ("seed" + std::to_string(seed));
    const auto r = run("sim --seed " + std::to_string(seed) + " --out \"" + dir.string() + "\"");
    EXPECT_EQ(r.code, 0) << r.out << r.err;
    return dir.string();
  };
  const std::string test = sim(kSeed);
  const std::string train = sim(kSeed + 101) + "," + sim(kSeed + 102) + "," + sim(kSeed + 103);
  const std::string validate = sim(kSeed + 202);

  const fs::path demo_json = root / "demo.json", run_json = root / "run.json", loaded_json = root / "loaded.json";
  const fs::path rec = root / "recogniser.txt";
  const auto demo = run("demo --seed " + std::to_string(kSeed) + " --json \"" + demo_json.string() + "\"");
  ASSERT_EQ(demo.code, 0) << demo.err;
  const auto r = run("run region-imm --data \"" + test + "\" --train \"" + train + "\" --validate \"" + validate + "\" --json \"" +
                     run_json.string() + "\" --save-recogniser \"" + rec.string() + "\"");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("Mean horizontal position error"), std::string::npos) << r.out;

  const json d = read_json(demo_json)["region_imm"];
  const json p = read_json(run_json)["pipeline"];
  ASSERT_TRUE(d.is_object() && !d.empty());
  const int compared = compare(d, p, "region_imm");
  EXPECT_GT(compared, 90) << "the demo's region_imm section is smaller than expected";

  // The saved recogniser, loaded without any training data, gives the same numbers again.
  const auto l = run("run region-imm --data \"" + test + "\" --recogniser \"" + rec.string() + "\" --json \"" + loaded_json.string() + "\"");
  ASSERT_EQ(l.code, 0) << l.out << l.err;
  compare(p, read_json(loaded_json)["pipeline"], "loaded");
  fs::remove_all(root.parent_path());
}

TEST(RunRegionImm, OptionsAreCheckedAndHelpListsThePipelinesAndTheirFiles) {
  const auto help = run("run --help");
  EXPECT_EQ(help.code, 0);
  for (const char* s : {"gnss", "region-imm", "sats.csv", "imu.csv"}) EXPECT_NE(help.out.find(s), std::string::npos) << s << "\n" << help.out;
  const auto sub = run("run region-imm --help");
  EXPECT_EQ(sub.code, 0);
  for (const char* s : {"--train", "--validate", "--recogniser", "--save-recogniser", "--data"})
    EXPECT_NE(sub.out.find(s), std::string::npos) << s << "\n" << sub.out;
  const fs::path dir = scratch("empty");
  // Training without validation, and neither training nor a recogniser: usage errors.
  auto r = run("run region-imm --data \"" + dir.string() + "\" --train \"" + dir.string() + "\"");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--validate"), std::string::npos) << r.err;
  r = run("run region-imm --data \"" + dir.string() + "\" --recogniser /nonexistent/file");
  EXPECT_EQ(r.code, 2) << r.err;
  fs::remove_all(dir.parent_path());
}

}  // namespace run_region_imm_cli

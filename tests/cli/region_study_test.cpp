// `ctxfuse region-study` (tools/cli/region_study.cpp), run as the built binary on one seed: the
// per-zone sensor picture and gate counts it prints and writes as JSON are checked against
// counts made here directly from sim::simulate_drive, its FKF / IMM errors against
// region_imm::run (the gate counting must not change the tracks), and bad flags must exit 2.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "ctxfuse/instances/region_imm.hpp"  // run() compiled once (ctxfuse::instances)
#include "ctxfuse/eval/region_errors.hpp"
#include "ctxfuse/pipelines/region_imm.hpp"
#include "ctxfuse/sim/drive.hpp"
#include "ctxfuse/sim/streams.hpp"
#include "ctxfuse/sim/scenarios.hpp"
#include "support/run_cli.hpp"

namespace fs = std::filesystem;
namespace ri = ctxfuse::pipelines::region_imm;
namespace sim = ctxfuse::sim;

// Named, not anonymous: the area's sources share one unity build (tests/CMakeLists.txt).
namespace region_study_cli {

ctxfuse::test::CliRun run(const std::string& args) { return ctxfuse::test::run_cli(args, ctxfuse::test::Stderr::separate); }

// ---- a small JSON reader (objects, arrays, numbers, strings, booleans), enough for the test
struct Value {
  enum Kind { number, string, boolean, array, object } kind = object;
  double num = 0.0;
  std::string str;
  bool flag = false;
  std::vector<Value> items;
  std::map<std::string, Value> members;
  const Value& operator[](const std::string& k) const {
    const auto it = members.find(k);
    if (it == members.end()) throw std::runtime_error("json: no member '" + k + "'");
    return it->second;
  }
  const Value& operator[](std::size_t i) const { return items.at(i); }
};

struct Reader {
  const std::string& s;
  std::size_t i = 0;
  void ws() {
    while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
  }
  void expect(char c) {
    ws();
    if (i >= s.size() || s[i] != c) throw std::runtime_error(std::string("json: expected '") + c + "' at " + std::to_string(i));
    ++i;
  }
  std::string text() {
    expect('"');
    std::string out;
    while (i < s.size() && s[i] != '"') {
      if (s[i] == '\\') ++i;
      out += s[i++];
    }
    ++i;
    return out;
  }
  Value value() {
    ws();
    Value v;
    if (s[i] == '{') {
      ++i;
      ws();
      if (s[i] == '}') return ++i, v;
      while (true) {
        std::string k = text();
        expect(':');
        v.members[k] = value();
        ws();
        if (s[i++] == '}') return v;
      }
    }
    if (s[i] == '[') {
      ++i;
      v.kind = Value::array;
      ws();
      if (s[i] == ']') return ++i, v;
      while (true) {
        v.items.push_back(value());
        ws();
        if (s[i++] == ']') return v;
      }
    }
    if (s[i] == '"') {
      v.kind = Value::string;
      v.str = text();
      return v;
    }
    if (s.compare(i, 4, "true") == 0 || s.compare(i, 5, "false") == 0) {
      v.kind = Value::boolean;
      v.flag = s[i] == 't';
      i += v.flag ? 4 : 5;
      return v;
    }
    v.kind = Value::number;
    std::size_t used = 0;
    v.num = std::stod(s.substr(i, 32), &used);
    i += used;
    return v;
  }
};

Value parse_json_file(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  Reader r{text};
  return r.value();
}

// ---- the zones, written here from the study's definition (tools/cli/region_study.cpp header):
// outdoor within 30 m of the approach's street mouth or not, street / door half of the
// approach, indoor within 10 m of the door plane x = 0 or deeper. The region is the one the
// simulator stamped on the measurement (GNSS) or of the truth sample nearest in time (UWB).
const std::array<std::string, 6> kZone{"out-far", "out-near", "tr-mouth", "tr-door", "in-door10", "in-deep"};

struct Zoner {
  const sim::Drive& d;
  double mouth_x;
  explicit Zoner(const sim::Drive& drive) : d(drive), mouth_x(1e300) {
    for (const auto& v : d.world().transition.vertices) mouth_x = std::min(mouth_x, v.x());
  }
  const sim::TruthSample& truth_near(double t) const {
    const auto it = std::lower_bound(d.truth.begin(), d.truth.end(), t, [](const sim::TruthSample& s, double x) { return s.t < x; });
    if (it == d.truth.end()) return d.truth.back();
    if (it != d.truth.begin() && t - std::prev(it)->t < it->t - t) return *std::prev(it);
    return *it;
  }
  std::size_t zone(double t, sim::Region region) const {
    const Eigen::Vector2d p = truth_near(t).position.head<2>();
    if (region == sim::Region::outdoor) return std::hypot(p.x() - mouth_x, p.y()) <= 30.0 ? 1 : 0;
    if (region == sim::Region::transition) return p.x() < mouth_x / 2.0 ? 2 : 3;
    return p.x() <= 10.0 ? 4 : 5;
  }
};

constexpr std::uint64_t kSeed = 3;

class RegionStudy : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() / ("ctxfuse_region_study_" + std::to_string(::getpid())));
    fs::create_directories(*dir_);
    const auto r = run("region-study --scenario default --seeds " + std::to_string(kSeed) + " --json \"" + (*dir_ / "s.json").string() + "\"");
    ASSERT_EQ(r.code, 0) << r.out << r.err;
    stdout_ = new std::string(r.out);
    json_ = new Value(parse_json_file(*dir_ / "s.json"));
    sim::DriveConfig cfg = sim::scenario_config("default");
    cfg.seed = kSeed;
    drive_ = new sim::Drive(sim::simulate_drive(cfg));
  }
  static void TearDownTestSuite() {
    if (dir_) fs::remove_all(*dir_);
    delete dir_;
    delete stdout_;
    delete json_;
    delete drive_;
  }
  static const Value& seed_doc() { return (*json_)["per_seed"][0]; }
  static inline fs::path* dir_ = nullptr;
  static inline std::string* stdout_ = nullptr;
  static inline Value* json_ = nullptr;
  static inline sim::Drive* drive_ = nullptr;
};

TEST_F(RegionStudy, GnssAndUwbCountsPerZoneMatchTheDrive) {
  ASSERT_NE(json_, nullptr);
  const sim::Drive& d = *drive_;
  const Zoner z(d);
  std::array<int, 6> epochs{}, fixes{}, ranges{}, nlos{};
  for (const auto& e : d.gnss) {
    const auto k = z.zone(e.t, e.region);
    ++epochs[k];
    fixes[k] += e.has_fix ? 1 : 0;
  }
  for (const auto& r : d.uwb) {
    const auto k = z.zone(r.t, z.truth_near(r.t).region);
    ++ranges[k];
    nlos[k] += r.nlos ? 1 : 0;
  }
  const Value& zones = seed_doc()["zones"];
  int total = 0;
  for (std::size_t k = 0; k < 6; ++k) {
    SCOPED_TRACE(kZone[k]);
    EXPECT_EQ(zones[kZone[k]]["gnss_epochs"].num, epochs[k]);
    EXPECT_EQ(zones[kZone[k]]["fixes"].num, fixes[k]);
    EXPECT_EQ(zones[kZone[k]]["ranges"].num, ranges[k]);
    EXPECT_EQ(zones[kZone[k]]["nlos_ranges"].num, nlos[k]);
    total += static_cast<int>(zones[kZone[k]]["gnss_epochs"].num);
  }
  EXPECT_EQ(total, static_cast<int>(d.gnss.size()));
  // The default scenario's anchors are in the garage and at the approach's door end: no range
  // reaches the street, nor the street half of the 138 m approach; the garage has no fix.
  for (std::size_t k : {0u, 1u, 2u}) EXPECT_EQ(zones[kZone[k]]["ranges"].num, 0) << kZone[k];
  for (std::size_t k : {4u, 5u}) EXPECT_EQ(zones[kZone[k]]["fixes"].num, 0) << kZone[k];
  EXPECT_GT(zones["in-deep"]["ranges"].num, 1000);
}

TEST_F(RegionStudy, PrintedTableIsTheJson) {
  ASSERT_NE(stdout_, nullptr);
  const Value& zones = seed_doc()["zones"];
  std::istringstream in(*stdout_);
  std::string line;
  int rows = 0;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string name;
    ls >> name;
    if (std::find(kZone.begin(), kZone.end(), name) == kZone.end() || line.find('|') == std::string::npos) continue;
    int gnss_epochs = -1, fixes = -1;
    ls >> gnss_epochs >> fixes;
    EXPECT_EQ(gnss_epochs, zones[name]["gnss_epochs"].num) << line;
    EXPECT_EQ(fixes, zones[name]["fixes"].num) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 6);
}

TEST_F(RegionStudy, FkfIsOfferedEveryUpdateAfterTheStart) {
  // The FKF takes every fix after the one it starts from (the dynamic alignment's, which the
  // pipeline reports) and every range after that time; its gate cannot reject more than it was
  // offered, nor accept NLOS ranges it was not offered.
  ASSERT_NE(json_, nullptr);
  const sim::Drive& d = *drive_;
  const Zoner z(d);
  const auto start = ri::run(sim::sensor_log(d), ri::Estimator::fkf, ri::Settings{}).alignment;
  ASSERT_TRUE(start.has_value());
  const double t0 = start->t;
  std::array<int, 6> fixes{}, ranges{}, nlos{};
  for (const auto& e : d.gnss)
    if (e.t > t0) fixes[z.zone(e.t, e.region)] += e.has_fix ? 1 : 0;
  for (const auto& r : d.uwb) {
    if (r.t <= t0 + 1e-9) continue;
    const auto k = z.zone(r.t, z.truth_near(r.t).region);
    ++ranges[k];
    nlos[k] += r.nlos ? 1 : 0;
  }
  const Value& fkf = seed_doc()["gates"]["fkf"];
  int gated = 0;
  for (std::size_t k = 0; k < 6; ++k) {
    SCOPED_TRACE(kZone[k]);
    EXPECT_EQ(fkf["gnss"][kZone[k]]["offered"].num, fixes[k]);
    EXPECT_EQ(fkf["uwb"][kZone[k]]["offered"].num, ranges[k]);
    EXPECT_EQ(fkf["uwb"][kZone[k]]["nlos_offered"].num, nlos[k]);
    EXPECT_LE(fkf["uwb"][kZone[k]]["gated"].num, ranges[k]);
    EXPECT_LE(fkf["uwb"][kZone[k]]["nlos_accepted"].num, nlos[k]);
    gated += static_cast<int>(fkf["uwb"][kZone[k]]["gated"].num);
  }
  EXPECT_GT(gated, 0);  // the 0.999 gate does reject NLOS ranges in the garage
  // The plain IMM's ODR never takes UWB, its IDR never takes GNSS.
  EXPECT_EQ(seed_doc()["gates"]["imm"]["uwb"]["odr"].kind, Value::string);
  EXPECT_EQ(seed_doc()["gates"]["imm"]["gnss"]["idr"].kind, Value::string);
}

TEST_F(RegionStudy, ErrorsAreThoseOfThePipelineAndTheSummaryAgrees) {
  ASSERT_NE(json_, nullptr);
  const ri::Settings s;
  const auto log = sim::sensor_log(*drive_);
  const auto fkf = ctxfuse::eval::region_errors(ri::run(log, ri::Estimator::fkf, s).track, drive_->truth);
  const auto imm = ctxfuse::eval::region_errors(ri::run(log, ri::Estimator::imm, s).track, drive_->truth);
  const Value& e = seed_doc()["mean_error_m"];
  const std::array<std::string, 4> col{"outdoor", "transition", "indoor", "overall"};
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_DOUBLE_EQ(e["fkf"][col[k]].num, fkf.mean[k]) << col[k];
    EXPECT_DOUBLE_EQ(e["imm"][col[k]].num, imm.mean[k]) << col[k];
  }
  const Value& row = (*json_)["summary"]["seeds"][0];
  EXPECT_EQ(row["seed"].num, kSeed);
  const double f = row["overall"]["fkf"].num, i = row["overall"]["imm"].num, r = row["overall"]["region_imm"].num;
  EXPECT_DOUBLE_EQ(f, fkf.mean[3]);
  EXPECT_DOUBLE_EQ(r, e["region_imm"]["overall"].num);
  EXPECT_EQ(row["overall"]["holds"].flag, r < i && i < f);
  EXPECT_EQ((*json_)["summary"]["overall_holds_count"].num, (r < i && i < f) ? 1 : 0);
  EXPECT_NE(stdout_->find("ordering holds overall on " + std::string((r < i && i < f) ? "1" : "0") + "/1 seeds"), std::string::npos);
}

TEST(RegionStudyUngated, NoUpdateIsGated) {
  const fs::path j = fs::temp_directory_path() / ("ctxfuse_region_study_ungated_" + std::to_string(::getpid()) + ".json");
  const auto r = run("region-study --ungated --seeds " + std::to_string(kSeed) + " --json \"" + j.string() + "\"");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  const Value doc = parse_json_file(j);
  fs::remove(j);
  EXPECT_TRUE(doc["ungated"].flag);
  int offered = 0;
  for (const char* est : {"imm", "region_imm"})
    for (const char* src : {"gnss", "uwb"})
      for (const char* taker : {"odr", "iotr", "idr", "imm"}) {
        const Value& t = doc["per_seed"][0]["gates"][est][src][taker];
        if (t.kind != Value::object) continue;
        for (const auto& zone : kZone) {
          EXPECT_EQ(t[zone]["gated"].num, 0) << est << ' ' << src << ' ' << taker << ' ' << zone;
          offered += static_cast<int>(t[zone]["offered"].num);
        }
      }
  EXPECT_GT(offered, 1000);
}

TEST(RegionStudyUsage, BadFlagsExitTwoNamingTheProblem) {
  struct Case {
    const char* args;
    const char* message;
  };
  for (const Case& c : {Case{"--scenario nope --seeds 1", "--scenario: nope not in {default,paper}"},
                        Case{"--seeds 5-2", "range '5-2' runs backwards"},
                        Case{"--seeds 1,x", "'x' is not a seed"},
                        Case{"--seeds 1,,2", "'' is not a seed"},
                        Case{"--seeds -3", "'' is not a seed"},
                        Case{"--seeds 1-3,2", "seed 2 listed twice"},
                        Case{"--seeds 99999999999", "'99999999999' is not a seed"},
                        Case{"--seeds", "--seeds: 1 required TEXT missing"},
                        Case{"--gate 0.9", "unknown option '--gate'"},
                        Case{"--indoor-fix-error x", "Could not convert: --indoor-fix-error = x"},
                        Case{"--indoor-fix-error -1", "gnss.indoor_fix_error_m must be finite and >= 0"},
                        Case{"--indoor-fix-reported-ratio 0", "gnss.indoor_fix_reported_ratio must be within (0, 100]"},
                        Case{"extra", "The following argument was not expected: extra"}}) {
    const auto r = run(std::string("region-study ") + c.args);
    EXPECT_EQ(r.code, 2) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << ": " << r.err;
    EXPECT_EQ(r.out.find("Summary"), std::string::npos) << c.args;  // nothing ran
  }
  const auto help = run("region-study --help");
  EXPECT_EQ(help.code, 0);
  EXPECT_NE(help.out.find("--ungated"), std::string::npos);
  EXPECT_NE(help.out.find("--indoor-fix-error"), std::string::npos);
}

}  // namespace region_study_cli

// `ctxfuse region-study`: why the region IMM does or does not beat the plain IMM and the FKF on
// a simulated drive. Per seed it prints the simulator's sensor picture per zone of the drive,
// how many GNSS and UWB updates each estimator's chi-square gate rejected per zone, and the
// errors; then a summary of the paper's ordering (region IMM < IMM < FKF) over the seeds.
// docs/results.md quotes its numbers, so every printed number is also in the --json document.
//
// Zones (truth position at the measurement time): out-far (outdoor, > 30 m from the approach's
// street mouth), out-near (outdoor within 30 m of it), tr-mouth / tr-door (street half / door
// half of the covered approach), in-door10 (indoor, within 10 m of the door plane x = 0),
// in-deep (the rest of the garage). They split the paper's three regions where the sensor
// picture changes: GNSS degrades towards the door, UWB (NLOS) away from it.
//
// Gate counts are read off each sink's per-source health counters (SourceHealth counts the
// unbroken run of gated updates; an update is gated exactly when that count went up by one),
// so the pipeline runs unchanged: the tracks are those of ri::run.
#include <algorithm>
#include <array>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <ostream>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "cli/cli_args.hpp"
#include "cli/json.hpp"
#include "cli/registry.hpp"
#include "cli/scenario_flag.hpp"
#include "ctxfuse/pipelines/region_imm.hpp"
#include "ctxfuse/sim/drive.hpp"

namespace ctxfuse::cli {
namespace {

namespace ri = pipelines::region_imm;

constexpr int kZones = 6;
constexpr std::array<const char*, kZones> kZoneName{"out-far", "out-near", "tr-mouth", "tr-door", "in-door10", "in-deep"};
constexpr double kNearMouthM = 30.0, kDoorDepthM = 10.0;

// ------------------------------------------------------------------ arguments
/// "1-5", "1,3,7", "2-4,9": ascending or not, each seed at most once.
bool parse_seeds(std::string_view text, std::vector<std::uint64_t>& seeds, std::ostream& err) {
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

std::string fmt(const char* f, auto... v) {
  char buf[512];
  std::snprintf(buf, sizeof buf, f, v...);
  return buf;
}

// ------------------------------------------------------------------ zones
struct Zoning {
  const sim::Drive& d;
  double mouth_x = 0.0;  // x of the approach's street end (west side of the transition polygon)
  explicit Zoning(const sim::Drive& drive) : d(drive), mouth_x(std::numeric_limits<double>::infinity()) {
    for (const auto& v : d.world().transition.vertices) mouth_x = std::min(mouth_x, v.x());
  }
  int at(const Eigen::Vector2d& p) const {
    switch (d.world().region_at(p)) {
      case sim::Region::outdoor: return (p - Eigen::Vector2d(mouth_x, 0.0)).norm() <= kNearMouthM ? 1 : 0;
      case sim::Region::transition: return p.x() < 0.5 * mouth_x ? 2 : 3;
      case sim::Region::indoor: return p.x() <= kDoorDepthM ? 4 : 5;
    }
    return 0;
  }
  int at_time(double t) const { return at(ri::detail::truth_at(d, t)); }
};

// ------------------------------------------------------------------ sensor picture
struct ZonePicture {
  int gnss_epochs = 0, fixes = 0;
  double fix_error_sum = 0.0, multipath_sum = 0.0;
  int uwb_epochs = 0, ranges = 0, nlos = 0;
  double range_error_sum = 0.0, nlos_bias_sum = 0.0, nlos_bias_max = 0.0;
  std::set<int> anchors;
};
using Picture = std::array<ZonePicture, kZones>;

Picture sensor_picture(const sim::Drive& d, const Zoning& zones) {
  Picture p;
  for (const auto& e : d.gnss) {
    auto& z = p[static_cast<std::size_t>(zones.at_time(e.t))];
    ++z.gnss_epochs;
    if (!e.has_fix) continue;
    ++z.fixes;
    z.fix_error_sum += e.error.head<2>().norm();
    z.multipath_sum += e.multipath_bias.head<2>().norm();
  }
  // Epochs of the UWB clock, whether or not any anchor answered.
  for (long k = 0;; ++k) {
    const double t = static_cast<double>(k) / d.config.uwb.rate_hz;
    if (t > d.duration()) break;
    ++p[static_cast<std::size_t>(zones.at_time(t))].uwb_epochs;
  }
  for (const auto& r : d.uwb) {
    auto& z = p[static_cast<std::size_t>(zones.at_time(r.t))];
    ++z.ranges;
    z.range_error_sum += r.range_m - r.true_range_m;
    z.anchors.insert(r.anchor_id);
    if (!r.nlos) continue;
    ++z.nlos;
    z.nlos_bias_sum += r.nlos_bias_m;
    z.nlos_bias_max = std::max(z.nlos_bias_max, r.nlos_bias_m);
  }
  return p;
}

double mean(double sum, int n) { return n > 0 ? sum / n : 0.0; }

void report_picture(const Picture& p, std::ostream& out, Json& json) {
  out << "  zone       gnssEp  fixes  fixErr   |mp|  | uwbEp  rng/ep  nlos%  nlosBias(max)  meanRngErr  anchors\n";
  for (int k = 0; k < kZones; ++k) {
    const auto& z = p[static_cast<std::size_t>(k)];
    std::string anchors;
    Json::Array ids;
    for (int a : z.anchors) {
      if (!anchors.empty()) anchors += ',';
      anchors += std::to_string(a);
      ids.emplace_back(a);
    }
    const double fix_err = mean(z.fix_error_sum, z.fixes), mp = mean(z.multipath_sum, z.fixes);
    const double per_epoch = mean(z.ranges, z.uwb_epochs), nlos_share = mean(z.nlos, z.ranges);
    const double bias = mean(z.nlos_bias_sum, z.nlos), range_err = mean(z.range_error_sum, z.ranges);
    out << fmt("  %-10s %6d %6d  %6.2f  %5.2f  | %5d  %5.2f  %5.1f  %5.2f (%5.2f)    %6.2f    %s\n", kZoneName[static_cast<std::size_t>(k)],
               z.gnss_epochs, z.fixes, fix_err, mp, z.uwb_epochs, per_epoch, 100.0 * nlos_share, bias, z.nlos_bias_max, range_err,
               anchors.empty() ? "-" : anchors.c_str());
    Json& j = json[kZoneName[static_cast<std::size_t>(k)]];
    j["gnss_epochs"] = z.gnss_epochs;
    j["fixes"] = z.fixes;
    j["fix_error_mean_m"] = fix_err;
    j["multipath_mean_m"] = mp;
    j["uwb_epochs"] = z.uwb_epochs;
    j["ranges"] = z.ranges;
    j["ranges_per_epoch"] = per_epoch;
    j["nlos_ranges"] = z.nlos;
    j["nlos_share"] = nlos_share;
    j["nlos_bias_mean_m"] = bias;
    j["nlos_bias_max_m"] = z.nlos_bias_max;
    j["range_error_mean_m"] = range_err;
    j["anchors"] = Json(std::move(ids));
  }
}

// ------------------------------------------------------------------ gate bookkeeping
// Takers of an update: the FKF's local filter (one column), or the IMM's modes ODR, I-OTR, IDR
// and the IMM as a whole (the update is gated by the IMM when no mode that took it accepted it;
// that is what ImmSink::imm_health counts for its lock-out recovery).
constexpr int kMaxTakers = 4;
constexpr std::array<const char*, kMaxTakers> kImmTaker{"odr", "iotr", "idr", "imm"};

struct ZoneGates {
  int offered = 0, gated = 0, nlos_offered = 0, nlos_accepted = 0;
};
using GateTable = std::array<std::array<std::array<ZoneGates, kZones>, kMaxTakers>, 2>;  // [gnss 0 / uwb 1][taker][zone]

template <class Sink>
std::array<int, kMaxTakers> rejection_counts(const Sink& sink, bool gnss) {
  auto of = [gnss](const ri::detail::FilterHealth& h) { return (gnss ? h.gnss : h.uwb).rejections(); };
  if constexpr (requires { sink.imm_health; })
    return {of(sink.health[0]), of(sink.health[1]), of(sink.health[2]), of(sink.imm_health)};
  else
    return {of(sink.health), 0, 0, 0};
}

template <class Sink>
std::array<bool, kMaxTakers> takers(const Sink& sink, bool gnss) {
  if constexpr (requires { sink.imm_health; }) {
    const std::uint32_t m = sink.mask(gnss);
    const bool odr = gnss && (m & 1u) != 0, iotr = (m & 2u) != 0, idr = !gnss && (m & 4u) != 0;
    return {odr, iotr, idr, odr || iotr || idr};
  } else {
    return {true, false, false, false};
  }
}

/// Forwards every call of ri::detail::replay to the sink and counts, per zone, the GNSS and
/// UWB updates each taker was offered and gated.
template <class Sink>
struct GateCounter {
  Sink& sink;
  const Zoning& zones;
  GateTable& table;
  void start(double t0, const Eigen::Vector2d& p0) { sink.start(t0, p0); }
  void predict(const models::PlanarImu& u, double dt) { sink.predict(u, dt); }
  void cycle_start() { sink.cycle_start(); }
  void speed(const sim::SpeedSample& v) { sink.speed(v); }
  void uwb(const sim::UwbRange& r) {
    count(false, r.t, r.nlos, [&] { sink.uwb(r); });
  }
  void gnss(const sim::GnssEpoch& e) {
    count(true, e.t, false, [&] { sink.gnss(e); });
  }
  void epoch_done(const sim::GnssEpoch& e) { sink.epoch_done(e); }

  template <class Update>
  void count(bool gnss, double t, bool nlos, Update&& update) {
    const auto zone = static_cast<std::size_t>(zones.at_time(t));
    const auto took = takers(sink, gnss);
    const auto before = rejection_counts(sink, gnss);
    update();
    const auto after = rejection_counts(sink, gnss);
    for (std::size_t j = 0; j < kMaxTakers; ++j) {
      if (!took[j]) continue;
      auto& c = table[gnss ? 0 : 1][j][zone];
      const bool gated = after[j] == before[j] + 1;
      ++c.offered;
      c.gated += gated ? 1 : 0;
      if (nlos) {
        ++c.nlos_offered;
        c.nlos_accepted += gated ? 0 : 1;
      }
    }
  }
};

template <class Sink>
ri::Track run_counting(const sim::Drive& d, const Zoning& zones, Sink& sink, GateTable& table) {
  GateCounter<Sink> counter{sink, zones, table};
  ri::detail::replay(d, counter);
  return sink.track;
}

void report_gates(const char* label, const GateTable& table, int taker_count, std::ostream& out, Json& json) {
  for (int src = 0; src < 2; ++src) {
    for (int j = 0; j < taker_count; ++j) {
      const auto& row = table[static_cast<std::size_t>(src)][static_cast<std::size_t>(j)];
      const char* taker = taker_count > 1 ? kImmTaker[static_cast<std::size_t>(j)] : "";
      out << fmt("    %-10s %s%s%-4s:", label, src == 0 ? "GNSS" : "UWB ", taker_count > 1 ? "/" : "", taker);
      Json& jt = taker_count > 1 ? json[src == 0 ? "gnss" : "uwb"][taker] : json[src == 0 ? "gnss" : "uwb"];
      if (std::none_of(row.begin(), row.end(), [](const ZoneGates& z) { return z.offered > 0; })) {
        out << " (never offered)\n";
        jt = Json("never offered");
        continue;
      }
      for (int k = 0; k < kZones; ++k) {
        const auto& z = row[static_cast<std::size_t>(k)];
        out << fmt("  %s %d/%d", kZoneName[static_cast<std::size_t>(k)], z.gated, z.offered);
        Json& jz = jt[kZoneName[static_cast<std::size_t>(k)]];
        jz["offered"] = z.offered;
        jz["gated"] = z.gated;
        if (src == 1) {
          jz["nlos_offered"] = z.nlos_offered;
          jz["nlos_accepted"] = z.nlos_accepted;
          if (z.nlos_offered > 0) out << fmt(" (nlos acc %d/%d)", z.nlos_accepted, z.nlos_offered);
        }
      }
      out << '\n';
    }
  }
}

// ------------------------------------------------------------------ one seed
struct SeedResult {
  std::uint64_t seed = 0;
  ri::TrackErrors fkf, imm, region_imm;
  bool overall_holds = false, transition_holds = false;
};

constexpr std::array<const char*, 4> kRegionColumn{"outdoor", "transition", "indoor", "overall"};

SeedResult study_seed(const sim::DriveConfig& cfg, const ri::Settings& s, std::ostream& out, Json& json) {
  const sim::Drive test = sim::simulate_drive(cfg);
  const Zoning zones(test);
  const auto f_test = ri::gnss_features(test);
  const ri::Recognition r = ri::recognise(ri::train_recogniser_for(test), f_test);

  out << fmt("\n=== seed %llu  (approach mouth at x = %.1f m; drive %.0f s)\n", static_cast<unsigned long long>(cfg.seed), zones.mouth_x,
             test.duration());
  json["seed"] = static_cast<double>(cfg.seed);
  json["approach_mouth_x_m"] = zones.mouth_x;
  json["duration_s"] = test.duration();
  report_picture(sensor_picture(test, zones), out, json["zones"]);

  GateTable g_fkf{}, g_imm{}, g_rimm{};
  ri::detail::Federated fkf{test, s, {}, {0.5, 0.5}, {}};
  const ri::Track t_fkf = run_counting(test, zones, fkf, g_fkf);
  ri::detail::ImmSink<policies::FixedTransition<3>> imm{
      test, s, policies::FixedTransition<3>(policies::sticky_transition<3>(s.stay_probability)), nullptr, nullptr, {}, {}};
  const ri::Track t_imm = run_counting(test, zones, imm, g_imm);
  ri::detail::ImmSink<policies::RegionAdaptiveTransition<3>> rimm{
      test, s,
      policies::RegionAdaptiveTransition<3>(policies::sticky_transition<3>(s.stay_probability), s.prior_weight, 1.0 - s.prior_weight),
      &r.joint, nullptr, {}, {}};
  const ri::Track t_rimm = run_counting(test, zones, rimm, g_rimm);

  out << "  gate rejections, gated/offered per zone (imm: no mode that took the update accepted it):\n";
  report_gates("FKF", g_fkf, 1, out, json["gates"]["fkf"]);
  report_gates("IMM", g_imm, kMaxTakers, out, json["gates"]["imm"]);
  report_gates("regionIMM", g_rimm, kMaxTakers, out, json["gates"]["region_imm"]);
  out << fmt("  UWB integrity re-anchorings (policies/integrity.hpp): FKF %d, IMM %d, region IMM %d\n", fkf.integrity.faults,
             imm.integrity.faults, rimm.integrity.faults);
  json["integrity_faults"]["fkf"] = fkf.integrity.faults;
  json["integrity_faults"]["imm"] = imm.integrity.faults;
  json["integrity_faults"]["region_imm"] = rimm.integrity.faults;

  SeedResult res;
  res.seed = cfg.seed;
  res.fkf = ri::errors(t_fkf);
  res.imm = ri::errors(t_imm);
  res.region_imm = ri::errors(t_rimm);
  struct Row {
    const char* label;
    const char* key;
    ri::TrackErrors e;
  };
  const std::array<Row, 7> rows{{
      {"GNSS", "gnss", ri::errors(ri::run(test, ri::Estimator::gnss, s))},
      {"UWB", "uwb", ri::errors(ri::run(test, ri::Estimator::uwb, s))},
      {"EKF-I-OTR", "iotr", ri::errors(ri::run(test, ri::Estimator::iotr, s))},
      {"FKF", "fkf", res.fkf},
      {"IMM", "imm", res.imm},
      {"region IMM", "region_imm", res.region_imm},
      {"rIMM truelab", "region_imm_true_labels", ri::errors(ri::run(test, ri::Estimator::region_imm, s, &f_test.truth))},
  }};
  out << "  mean horizontal error (m) at the GNSS epochs, per true region: outdoor transition indoor overall\n";
  for (const auto& row : rows) {
    out << fmt("    %-14s %7.3f %7.3f %7.3f %7.3f\n", row.label, row.e.mean[0], row.e.mean[1], row.e.mean[2], row.e.mean[3]);
    for (std::size_t k = 0; k < 4; ++k) json["mean_error_m"][row.key][kRegionColumn[k]] = row.e.mean[k];
  }
  const double a_svm = ri::accuracy(f_test.truth, r.svm), a_hmm = ri::accuracy(f_test.truth, r.hmm),
               a_joint = ri::accuracy(f_test.truth, r.joint);
  out << fmt("  region recognition accuracy SVM/HMM/joint %.2f/%.2f/%.2f %%\n", 100.0 * a_svm, 100.0 * a_hmm, 100.0 * a_joint);
  json["recognition_accuracy"]["svm"] = a_svm;
  json["recognition_accuracy"]["hmm"] = a_hmm;
  json["recognition_accuracy"]["joint"] = a_joint;

  res.overall_holds = res.region_imm.mean[3] < res.imm.mean[3] && res.imm.mean[3] < res.fkf.mean[3];
  res.transition_holds = res.region_imm.mean[1] < res.imm.mean[1] && res.imm.mean[1] < res.fkf.mean[1];
  json["ordering"]["overall_holds"] = res.overall_holds;
  json["ordering"]["transition_holds"] = res.transition_holds;
  return res;
}

void report_summary(const std::vector<SeedResult>& results, std::string_view header, std::ostream& out, Json& json) {
  out << "\nSummary (" << header << "): mean horizontal error (m); ordering = region IMM < IMM < FKF\n";
  out << "  seed |  overall: FKF     IMM    rIMM  ordering | transition: FKF     IMM    rIMM  ordering\n";
  int overall = 0, transition = 0;
  std::array<double, 6> sum{};
  Json rows = Json::array();
  for (const auto& r : results) {
    out << fmt("  %4llu |        %6.3f  %6.3f  %6.3f  %-8s |           %6.3f  %6.3f  %6.3f  %s\n", static_cast<unsigned long long>(r.seed),
               r.fkf.mean[3], r.imm.mean[3], r.region_imm.mean[3], r.overall_holds ? "holds" : "no", r.fkf.mean[1], r.imm.mean[1],
               r.region_imm.mean[1], r.transition_holds ? "holds" : "no");
    overall += r.overall_holds ? 1 : 0;
    transition += r.transition_holds ? 1 : 0;
    const std::array<double, 6> v{r.fkf.mean[3], r.imm.mean[3], r.region_imm.mean[3], r.fkf.mean[1], r.imm.mean[1], r.region_imm.mean[1]};
    for (std::size_t k = 0; k < v.size(); ++k) sum[k] += v[k];
    Json row;
    row["seed"] = static_cast<double>(r.seed);
    row["overall"]["fkf"] = v[0];
    row["overall"]["imm"] = v[1];
    row["overall"]["region_imm"] = v[2];
    row["overall"]["holds"] = r.overall_holds;
    row["transition"]["fkf"] = v[3];
    row["transition"]["imm"] = v[4];
    row["transition"]["region_imm"] = v[5];
    row["transition"]["holds"] = r.transition_holds;
    rows.push_back(std::move(row));
  }
  const double n = static_cast<double>(results.size());
  out << fmt("  mean |        %6.3f  %6.3f  %6.3f  %2d/%-5zu |           %6.3f  %6.3f  %6.3f  %d/%zu\n", sum[0] / n, sum[1] / n, sum[2] / n,
             overall, results.size(), sum[3] / n, sum[4] / n, sum[5] / n, transition, results.size());
  out << fmt("ordering holds overall on %d/%zu seeds, in the transition region on %d/%zu\n", overall, results.size(), transition,
             results.size());
  json["seeds"] = std::move(rows);
  json["mean_over_seeds"]["overall"]["fkf"] = sum[0] / n;
  json["mean_over_seeds"]["overall"]["imm"] = sum[1] / n;
  json["mean_over_seeds"]["overall"]["region_imm"] = sum[2] / n;
  json["mean_over_seeds"]["transition"]["fkf"] = sum[3] / n;
  json["mean_over_seeds"]["transition"]["imm"] = sum[4] / n;
  json["mean_over_seeds"]["transition"]["region_imm"] = sum[5] / n;
  json["overall_holds_count"] = overall;
  json["transition_holds_count"] = transition;
  json["seed_count"] = static_cast<double>(results.size());
}

// ------------------------------------------------------------------ command
int region_study(Args args, std::ostream& out, std::ostream& err) {
  if (wants_help(args)) {
    out << "usage: ctxfuse region-study " << kScenarioFlagsUsage << " [--seeds LIST] [--ungated] [--no-integrity] [--json FILE]\n"
        << "Per simulated drive (seed): the sensor picture per zone of the drive (out-far, out-near = within\n"
           "30 m of the approach mouth, tr-mouth / tr-door = street / door half of the approach, in-door10 =\n"
           "indoor within 10 m of the door, in-deep), the GNSS/UWB updates each estimator's chi-square gate\n"
           "rejected per zone (FKF; plain IMM and region IMM per mode and as a whole), the mean errors, and\n"
           "a summary of region IMM < IMM < FKF over the seeds. The recogniser is trained as in\n"
           "`ctxfuse demo` (seeds N+101..N+103, validation N+202).\n"
           "  --seeds LIST     e.g. 1-5, 1,3,7 or 1-3,9 (default: 1-5)\n"
           "  --ungated        no chi-square gate (gate probability 1; the lock-out recovery never fires)\n"
           "  --no-integrity   no UWB integrity check (Settings::uwb_integrity off: no re-anchoring to\n"
           "                   snapshot multilaterations)\n"
           "  --json FILE      every printed number also as JSON\n"
        << kScenarioFlagsHelp;
    return 0;
  }
  // FlagParser takes flags with values only; --ungated and --no-integrity are switches.
  std::vector<std::string_view> rest;
  bool ungated = false, no_integrity = false;
  for (auto a : args) {
    if (a == "--ungated")
      ungated = true;
    else if (a == "--no-integrity")
      no_integrity = true;
    else
      rest.push_back(a);
  }
  FlagParser flags("region-study", with_scenario_flags({"--seeds", "--json"}));
  if (!flags.parse(Args(rest), err)) return 2;
  if (!flags.positionals().empty()) {
    err << "ctxfuse region-study: unexpected argument '" << flags.positionals()[0] << "'\n";
    return 2;
  }
  const std::string scenario = scenario_label(flags);
  const std::optional<sim::DriveConfig> base = scenario_from_flags(flags, "region-study", err);
  if (!base) return 2;
  std::vector<std::uint64_t> seeds;
  if (!parse_seeds(flags.get("--seeds").value_or("1-5"), seeds, err)) return 2;
  const auto json_path = flags.get("--json");
  // Tried before the study runs, so that a bad path fails at once.
  if (json_path && !write_json_file(Json{}, *json_path, "region-study", err)) return 1;

  ri::Settings settings;
  if (ungated) settings.gate_probability = 1.0;
  settings.uwb_integrity = !no_integrity;
  const std::string header = "scenario " + scenario + ", " + (ungated ? std::string("ungated") : fmt("gate %g", settings.gate_probability)) +
                             (no_integrity ? ", no integrity check" : "");
  out << "region study: " << header << "\n";
  Json doc;
  doc["scenario"] = scenario;
  doc["ungated"] = ungated;
  doc["uwb_integrity"] = !no_integrity;
  doc["gate_probability"] = settings.gate_probability;
  Json per_seed = Json::array();
  std::vector<SeedResult> results;
  for (const std::uint64_t seed : seeds) {
    sim::DriveConfig cfg = *base;
    cfg.seed = seed;
    Json j;
    results.push_back(study_seed(cfg, settings, out, j));
    per_seed.push_back(std::move(j));
    out.flush();
  }
  doc["per_seed"] = std::move(per_seed);
  report_summary(results, header, out, doc["summary"]);
  if (json_path && !write_json_file(doc, *json_path, "region-study", err)) return 1;
  return 0;
}

const RegisterCommand reg{{"region-study", "sensor picture, gate rejections and errors per zone (region IMM vs IMM vs FKF)", region_study}};

}  // namespace
}  // namespace ctxfuse::cli

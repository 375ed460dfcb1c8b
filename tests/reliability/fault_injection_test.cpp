// Fault injection on the simulated drive (issue 18 item 2), through the replay's tamper hook,
// for the region-aware IMM, the federated filter and GNSS alone. For every fault and pipeline:
//  - the evidence that it was seen: the replay report's drop counts (stamps), the refused IMU
//    samples, the gated updates (observer), or for values an estimator refuses, a track
//    identical to the one without those messages (refused and nothing lost);
//  - after every step (IMU propagation, measurement): every belief finite, its covariance
//    symmetric and positive definite (BeliefChecks);
//  - recovery: from `recovery_s` after the fault is over and for `window_s` after that, the
//    position error at every receiver epoch is within twice the larger of the clean run's
//    95th percentile in the epoch's true region and the clean run's own error at that epoch.
//    The percentile per region scales the bound to each pipeline and place (centimetres
//    under UWB in the garage, metres under GNSS outside; GNSS alone holds its last fix
//    through the garage); the clean error at the epoch keeps epochs where the clean run is
//    itself worse than usual from failing on what the fault did not cause.
// The regions of the region IMM are the true labels: the faults test the estimator, not the
// recogniser. Settings are the pipeline's defaults (ri::Settings{}), and for the speed values
// also with the speed update on (use_speed), the only setting under which they are read.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>
#include <span>
#include <tuple>
#include <utility>
#include <string>
#include <cstdio>
#include <limits>
#include <vector>

#include "ctxfuse/eval/position_error.hpp"
#include "ctxfuse/instances/region_imm.hpp"  // region_imm::run compiled once (ctxfuse::instances)
#include "ctxfuse/eval/region_errors.hpp"
#include "ctxfuse/pipelines/region_imm/recogniser.hpp"
#include "ctxfuse/sim/scenarios.hpp"
#include "ctxfuse/sim/streams.hpp"
#include "fault_injection.hpp"

// Named, not anonymous: the area's sources share one unity build (tests/CMakeLists.txt).
namespace fault_injection {
using namespace ctxfuse;
using namespace ctxfuse::reliability;
namespace ri = pipelines::region_imm;

constexpr double recovery_s = 20.0, window_s = 30.0;

// Faults start 60 s into the drive (outdoors, moving, well after the alignment) and in the
// middle of the indoor stretch (SimulatedDrive::indoor_middle).
constexpr double kOutdoorFault = 60.0;

const SimulatedDrive& drive() { return simulated_drive(); }

/// The true regions at the receiver epochs (the region IMM's labels).
const ri::RegionTrack& regions() {
  static const ri::RegionTrack r = [] {
    const auto features = ri::gnss_features(drive().log.sat_epochs);
    return ri::region_track(features, eval::region_labels(drive().drive.truth, features.t));
  }();
  return r;
}

enum class Pipeline { region_imm, fkf, gnss };
const char* name(Pipeline p) { return p == Pipeline::region_imm ? "region IMM" : p == Pipeline::fkf ? "FKF" : "GNSS alone"; }

struct CountGated {
  const Fault* fault = nullptr;
  std::size_t gnss_gated = 0, uwb_gated = 0;  // by the estimator as a whole, inside the fault window
  void operator()(const ri::UpdateEvent& ev) {
    if (!fault || ev.t < fault->stamped(fault->begin) || ev.t >= fault->stamped(fault->end) + 1.0) return;
    if (!ev.gated[static_cast<std::size_t>(ev.takers - 1)]) return;
    ++(ev.source == ri::Source::gnss ? gnss_gated : uwb_gated);
  }
};

struct Outcome {
  io::ReplayReport<4> replay;
  ri::Track track;
  BeliefChecks checks;
  CountGated gated;
};

/// A faulted run replays the log only up to the end of its check window (and 2 s more): what
/// comes after cannot change what is checked (the estimators are causal), and the clean run it
/// is compared with is the full drive's, whose prefix is the same. This keeps the test cheap
/// enough for the sanitizer build.
double stop_time(const Fault* f) {
  return f ? f->over() + recovery_s + window_s + 2.0 : std::numeric_limits<double>::infinity();
}

template <class Est>
void replay_into(Est& est, const Fault* f, const ri::Settings& s, Outcome& out) {
  const std::optional<ri::KnownMotion> known;
  Checked<Est> h{{est, s, known}};
  const auto& log = drive().log;
  const double stop = stop_time(f);
  auto go = [&](auto tamper) {
    return io::replay_tampered(h, tamper, before(log.imu, stop), before(log.speed, stop), before(log.uwb, stop),
                               before(log.gnss, stop), before(log.sat_epochs, stop));
  };
  out.replay = f ? go(FaultTamper(*f)) : go(io::NoTamper{});
  EXPECT_TRUE(h.runner.started);
  out.checks = h.checks;
  if constexpr (requires { est.track(); })
    out.track = est.track();
  else
    out.track = est.track;
}

/// The pipeline's default settings, and the same with the speed update (the speed samples'
/// values read) instead of the non-holonomic constraint alone.
const ri::Settings& defaults() {
  static const ri::Settings s;
  return s;
}
const ri::Settings& with_speed() {
  static const ri::Settings s = [] {
    ri::Settings x;
    x.use_speed = true;
    return x;
  }();
  return s;
}

Outcome run(Pipeline p, const Fault* f, const ri::Settings& s = defaults()) {
  Outcome out;
  out.gated.fault = f;
  switch (p) {
    case Pipeline::region_imm: {
      using M = policies::RegionAdaptiveTransition<3>;
      ri::Aided<ri::ImmCore<M>> est(ri::ImmCore<M>{&s, ri::detail::make_mixing<M>(s), &regions()}, s,
                                                &out.gated);
      replay_into(est, f, s, out);
      break;
    }
    case Pipeline::fkf: {
      ri::Aided<ri::FederatedCore> est(ri::FederatedCore{&s}, s, &out.gated);
      replay_into(est, f, s, out);
      break;
    }
    case Pipeline::gnss: {
      ri::GnssOnly est;
      replay_into(est, f, s, out);
      break;
    }
  }
  return out;
}

/// Horizontal error at each track epoch; `post_from`: the first index whose stamp is after a
/// clock jump (its original time is the stamp minus the jump).
std::vector<double> errors(const ri::Track& tr, const Fault* f, std::size_t post_from) {
  std::vector<double> e(tr.t.size());
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    const double t = f && f->kind == FaultKind::clock_jump && i >= post_from ? tr.t[i] - f->clock_jump_s : tr.t[i];
    e[i] = (tr.estimate[i] - eval::position_at(drive().drive.truth, t).head<2>()).norm();
  }
  return e;
}

/// Original time of each epoch of a faulted track (see errors()).
double original_time(const ri::Track& tr, const Fault& f, std::size_t i, std::size_t post_from) {
  return f.kind == FaultKind::clock_jump && i >= post_from ? tr.t[i] - f.clock_jump_s : tr.t[i];
}

const Outcome& clean(Pipeline p, const ri::Settings& s = defaults()) {
  static std::map<std::pair<Pipeline, bool>, Outcome> cache;
  auto it = cache.find({p, s.use_speed});
  if (it == cache.end()) it = cache.emplace(std::pair{p, s.use_speed}, run(p, nullptr, s)).first;
  return it->second;
}

/// 95th percentile of a clean run's errors per true region (outdoor, transition, indoor).
std::array<double, 3> region_p95(const ri::Track& tr, const std::vector<double>& err) {
  std::array<std::vector<double>, 3> by;
  for (std::size_t i = 0; i < tr.t.size(); ++i)
    by[static_cast<std::size_t>(eval::region_at(drive().drive.truth, tr.t[i]))].push_back(err[i]);
  std::array<double, 3> p{};
  for (std::size_t r = 0; r < 3; ++r) p[r] = eval::percentile(by[r], 95.0);
  return p;
}

/// The dropout of the same stream and window: what a refused value must be identical to.
Fault as_dropout(const Fault& f) {
  Fault d = f;
  d.kind = FaultKind::dropout;
  return d;
}

/// Whether track `a` is the first epochs of track `b`, bit for bit.
bool same_track(const ri::Track& a, const ri::Track& b) {
  return a.t.size() <= b.t.size() && std::equal(a.t.begin(), a.t.end(), b.t.begin()) &&
         std::equal(a.estimate.begin(), a.estimate.end(), b.estimate.begin());
}

/// The track of the dropout of a fault's stream and window (a NaN and an Inf fault share it).
const ri::Track& dropout_track(Pipeline p, const Fault& f, const ri::Settings& s) {
  static std::map<std::tuple<Pipeline, bool, StreamId, double, double>, ri::Track> cache;
  const auto key = std::tuple{p, s.use_speed, f.stream, f.begin, f.end};
  auto it = cache.find(key);
  if (it == cache.end()) {
    const Fault d = as_dropout(f);
    it = cache.emplace(key, run(p, &d, s).track).first;
  }
  return it->second;
}

bool reads(Pipeline p, StreamId s) {
  if (p == Pipeline::gnss) return s == StreamId::gnss || s == StreamId::sat_epochs || s == StreamId::all;
  return true;
}

/// The evidence of a NaN or infinite value: the pipeline refuses it (counted for the IMU and the
/// speed update) and its track is the dropout's; a speed the default settings do not read
/// changes nothing.
std::string refused_evidence(Pipeline p, const Fault& f, const ri::Settings& s, const ri::Track& base, const ri::Track& out,
                             std::size_t n) {
  if (f.stream == StreamId::imu) {
    EXPECT_EQ(out.rejected_imu - base.rejected_imu, n);
    return format("%zu IMU samples refused, the previous one held (Track::rejected_imu)", out.rejected_imu - base.rejected_imu);
  }
  if (f.stream == StreamId::speed && !s.use_speed) {
    // With the default settings the speed's value is not read (the samples time the
    // non-holonomic constraint), so nothing may change.
    EXPECT_TRUE(same_track(out, base));
    return "value not read (NHC): track identical";
  }
  const ri::Track& dropped = dropout_track(p, f, s);
  EXPECT_TRUE(out.t.size() == dropped.t.size() && same_track(out, dropped));
  if (f.stream != StreamId::speed) return "refused: track identical to the dropout's";
  EXPECT_EQ(out.rejected_speed - base.rejected_speed, n);  // the speed update's refusals are counted
  return format("%zu refused (Track::rejected_speed): track identical to the dropout's", out.rejected_speed - base.rejected_speed);
}

/// Runs one fault on one pipeline, checks it, and prints its row of the table.
void check_fault(Pipeline p, const Fault& f, const ri::Settings& s = defaults()) {
  SCOPED_TRACE(std::string(name(p)) + ": " + f.name);
  const Outcome& base = clean(p, s);
  const Outcome out = run(p, &f, s);
  EXPECT_TRUE(out.checks.clean()) << "non-finite " << out.checks.non_finite << ", asymmetric " << out.checks.asymmetric
                                  << ", not PD " << out.checks.not_pd << " of " << out.checks.checked;

  // The evidence.
  const std::size_t n = messages_in(drive().log, f.stream == StreamId::all ? StreamId::imu : f.stream, f.begin, f.end);
  const io::StreamReport& rep = report_of(out.replay, f.stream);
  std::string evidence;
  if (!reads(p, f.stream)) {
    // A stream the pipeline does not read: nothing may change.
    EXPECT_TRUE(same_track(out.track, base.track));
    evidence = "stream not read: track identical";
  } else if (f.kind == FaultKind::nan_value || f.kind == FaultKind::inf_value) {
    evidence = refused_evidence(p, f, s, base.track, out.track, n);
  } else if (const auto replayed = replay_evidence(f, rep, n)) {
    // The region table's wording (docs/reliability.md): both copy counts, and the order
    // fault's count without "(replay report)".
    if (f.kind == FaultKind::duplicate)
      evidence = format("%zu repeated + %zu duplicate dropped", rep.repeated, rep.duplicate);
    else if (f.kind == FaultKind::out_of_order)
      evidence = format("%zu backwards dropped", rep.backwards);
    else
      evidence = *replayed;
  } else if (f.kind == FaultKind::gnss_jump) {
    if (p != Pipeline::gnss) {
      EXPECT_GE(out.gated.gnss_gated, 1u);
      evidence = format("%zu of %zu jumped fixes gated", out.gated.gnss_gated, n);
    } else {
      evidence = "none: GNSS alone reports the receiver's fix";
    }
  } else if (f.kind == FaultKind::clock_jump) {
    if (f.clock_jump_s < 0.0) {
      EXPECT_GT(out.replay.imu.backwards, 0u);
      evidence = format("backwards dropped: imu %zu, uwb %zu, gnss %zu, epochs %zu", out.replay.imu.backwards,
                        out.replay.streams[1].backwards, out.replay.streams[2].backwards, out.replay.streams[3].backwards);
    } else if (p != Pipeline::gnss) {
      // 5 s of dead reckoning at 6 m/s put the prediction about 30 m ahead of the next
      // fix, far outside a 0.999 gate on metre-level fixes.
      EXPECT_GE(out.gated.gnss_gated, 1u);
      evidence = format("%zu fixes gated", out.gated.gnss_gated);
    } else {
      evidence = "none: GNSS alone has no clock of its own";
    }
  } else if (f.kind == FaultKind::wrong_anchor) {
    evidence = format("%zu ranges gated, %d integrity faults", out.gated.uwb_gated, out.track.integrity_faults);
  }

  // Recovery.
  const auto base_err = errors(base.track, nullptr, 0);
  const auto p95 = region_p95(base.track, base_err);
  std::size_t post_from = 0;
  while (post_from < base.track.t.size() && base.track.t[post_from] < f.begin) ++post_from;
  const auto err = errors(out.track, &f, post_from);
  Recovery rec{f, recovery_s, window_s};
  for (std::size_t i = 0; i < out.track.t.size(); ++i) {
    const double t = original_time(out.track, f, i, post_from);
    if (!rec.take(t, err[i])) continue;
    // The clean run's epoch at the same original time.
    const auto j = static_cast<std::size_t>(std::lower_bound(base.track.t.begin(), base.track.t.end(), t) - base.track.t.begin());
    ASSERT_LT(j, base.track.t.size());
    rec.check(t, err[i], 2.0 * std::max(p95[static_cast<std::size_t>(eval::region_at(drive().drive.truth, t))], base_err[j]));
  }
  EXPECT_GE(rec.checked, static_cast<std::size_t>(window_s) - 2);
  std::printf("| %s | %s | %s | %.2f | %.2f | %.2f |\n", f.name.c_str(), name(p), evidence.c_str(), rec.during, rec.worst,
              rec.share);
}

std::vector<Fault> outdoor_faults() {
  const double t = kOutdoorFault;
  std::vector<Fault> v{
      fault_window("GNSS NaN 5 s", FaultKind::nan_value, StreamId::gnss, t, 5.0),
      fault_window("GNSS Inf 5 s", FaultKind::inf_value, StreamId::gnss, t, 5.0),
      fault_window("GNSS +100 m 10 s", FaultKind::gnss_jump, StreamId::gnss, t, 10.0),
      fault_window("GNSS dropout 10 s", FaultKind::dropout, StreamId::gnss, t, 10.0),
      fault_window("GNSS duplicated 10 s", FaultKind::duplicate, StreamId::gnss, t, 10.0),
      fault_window("GNSS out of order 10 s", FaultKind::out_of_order, StreamId::gnss, t, 10.0),
      fault_window("epochs NaN stamp 5 s", FaultKind::nan_stamp, StreamId::sat_epochs, t, 5.0),
      fault_window("epochs dropout 10 s", FaultKind::dropout, StreamId::sat_epochs, t, 10.0),
  };
  Fault ahead = fault_window("clock +5 s", FaultKind::clock_jump, StreamId::all, t + 0.5, 0.0);
  Fault back = ahead;
  back.name = "clock -2 s";
  back.clock_jump_s = -2.0;
  v.push_back(ahead);
  v.push_back(back);
  return v;
}

std::vector<Fault> indoor_faults(StreamId s, const char* what) {
  const double t = drive().indoor_middle;
  const std::string w = what;
  std::vector<Fault> v{
      fault_window(w + " NaN 5 s", FaultKind::nan_value, s, t, 5.0),
      fault_window(w + " Inf 5 s", FaultKind::inf_value, s, t, 5.0),
      fault_window(w + " dropout 10 s", FaultKind::dropout, s, t, 10.0),
      fault_window(w + " duplicated 10 s", FaultKind::duplicate, s, t, 10.0),
      fault_window(w + " out of order 10 s", FaultKind::out_of_order, s, t, 10.0),
  };
  if (s == StreamId::uwb) v.push_back(fault_window("UWB anchor 5 m off 30 s", FaultKind::wrong_anchor, s, t, 30.0));
  return v;
}

void check_all(const std::vector<Fault>& faults) {
  for (Pipeline p : {Pipeline::region_imm, Pipeline::fkf, Pipeline::gnss})
    for (const Fault& f : faults) check_fault(p, f);
}

TEST(FaultInjection, CleanRunsAreClean) {
  for (Pipeline p : {Pipeline::region_imm, Pipeline::fkf, Pipeline::gnss}) {
    const Outcome& o = clean(p);
    EXPECT_TRUE(o.checks.clean()) << name(p);
    EXPECT_EQ(o.replay.dropped(), 0u) << name(p);
    const auto e = errors(o.track, nullptr, 0);
    const auto p95 = region_p95(o.track, e);
    std::printf("clean %s: %zu epochs, error p95 outdoor %.2f m, transition %.2f m, indoor %.2f m, max %.2f m; faults at %.1f s "
                "(outdoor) and %.1f s (indoor)\n",
                name(p), e.size(), p95[0], p95[1], p95[2], *std::max_element(e.begin(), e.end()), kOutdoorFault,
                drive().indoor_middle);
  }
}

// The bug this test found: a fix with a NaN position became GNSS alone's reported position
// from then on. Now such a fix is no fix: the last position is held without a solution.
TEST(FaultInjection, GnssAloneHoldsItsLastPositionThroughANonFiniteFix) {
  ri::GnssOnly est;
  est.start(0.0, Gaussian<ri::L::size>{});
  messages::GnssFix fix;
  fix.t = 1.0;
  fix.position = Eigen::Vector3d(3.0, 4.0, 0.0);
  est.gnss(fix);
  est.epoch(1.0);
  fix.t = 2.0;
  fix.position.x() = std::numeric_limits<double>::quiet_NaN();
  est.gnss(fix);
  est.epoch(2.0);
  ASSERT_EQ(est.track.estimate.size(), 2u);
  EXPECT_EQ(est.track.estimate[1], Eigen::Vector2d(3.0, 4.0));
  EXPECT_TRUE(est.track.solution[0]);
  EXPECT_FALSE(est.track.solution[1]);
}

TEST(FaultInjection, GnssEpochsAndClock) { check_all(outdoor_faults()); }
TEST(FaultInjection, Imu) { check_all(indoor_faults(StreamId::imu, "IMU")); }
TEST(FaultInjection, Speed) { check_all(indoor_faults(StreamId::speed, "speed")); }
TEST(FaultInjection, Uwb) { check_all(indoor_faults(StreamId::uwb, "UWB")); }
// The speed samples' values are read only with the speed update (Settings::use_speed); with it
// a NaN or infinite speed must be refused as its dropout would be.
TEST(FaultInjection, SpeedWithTheSpeedUpdate) {
  auto faults = indoor_faults(StreamId::speed, "speed (use_speed)");
  faults.resize(2);  // NaN and Inf
  for (Pipeline p : {Pipeline::region_imm, Pipeline::fkf})
    for (const Fault& f : faults) check_fault(p, f, with_speed());
}

}  // namespace fault_injection

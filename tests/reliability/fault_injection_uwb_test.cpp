// Fault injection (issue 18 item 2) on the NLOS-robust UWB pipeline (pipelines/nlos_uwb): the
// range EKF under the innovation gate, without NLOS handling (every range attached, so the
// faults test the estimator and the replay, not the classifier), on the simulated drive's
// ranges (the default scenario, seed 11, as the region pipeline's fault test). The run is the
// pipeline's own (EpochAssembler + EpochProcessor, as nlos_uwb::run) over io::replay_tampered.
// For every fault:
//  - evidence: the replay report's drop counts equal the touched ranges (stamps, dropouts,
//    duplicates, order), the estimator refused every touched range (NaN / Inf: counted in
//    Track::ranges_invalid), or the gate refused the wrong anchor's ranges;
//  - after every epoch: the EKF's belief finite, its covariance symmetric positive definite;
//  - recovery: from recovery_s after the fault is over, for window_s, the error of every
//    estimate within twice the larger of the clean run's 95th percentile and the clean run's
//    error at the same time.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "ctxfuse/eval/position_error.hpp"
#include "ctxfuse/eval/region_errors.hpp"
#include "ctxfuse/pipelines/nlos_uwb/run.hpp"
#include "ctxfuse/sim/scenarios.hpp"
#include "ctxfuse/sim/streams.hpp"
#include "fault_stream.hpp"

// Named, not anonymous: the area's sources share one unity build (tests/CMakeLists.txt).
namespace fault_injection_uwb {
using namespace ctxfuse;
using namespace ctxfuse::reliability;
namespace nu = pipelines::nlos_uwb;

constexpr double recovery_s = 10.0, window_s = 20.0;

const SimulatedDrive& drive() { return simulated_drive(); }
/// Where the faults start: the middle of the indoor stretch.
double fault_time() { return drive().indoor_middle; }
const std::vector<messages::UwbRange>& ranges() { return drive().log.uwb; }

const nu::Settings& settings() {
  static const nu::Settings s;
  return s;
}

using Ekf = nu::RangeEkf<>;

/// The pipeline's epoch processor with the belief checks after every epoch.
struct CheckedEpochs {
  nu::EpochProcessor<Ekf, nu::NoNlosHandling>& process;
  const Ekf& est;
  BeliefChecks& checks;
  void operator()(std::span<const messages::UwbRange> epoch) {
    process(epoch);
    if (est.started()) checks.check(est.belief());
  }
};

struct RunOutcome {
  io::ReplayReport<1> replay;
  nu::Track track;
  BeliefChecks checks;
};

/// A run replays the ranges up to the end of the check window of `f` (all the indoor stretch's
/// check windows for the clean run): the estimator is causal, so nothing later changes them.
RunOutcome run(const Fault* f) {
  RunOutcome out;
  const nu::Settings& s = settings();
  Ekf est(s);
  const nu::NoNlosHandling policy;
  nu::NlosClassifier classifier(s);
  nu::EpochProcessor<Ekf, nu::NoNlosHandling> process(s, est, policy, classifier, out.track);
  CheckedEpochs checked{process, est, out.checks};
  nu::EpochAssembler<CheckedEpochs> epochs(s.epoch_window_s, checked);
  nu::RangeHandler<decltype(epochs)> handler{epochs};
  const double stop = fault_time() + 30.0 + recovery_s + window_s + 2.0;
  const auto until = before(ranges(), stop);
  const std::span<const messages::ImuSample> no_imu;
  out.replay = f ? io::replay_tampered(handler, FaultTamper(*f), no_imu, until)
                 : io::replay_tampered(handler, io::NoTamper{}, no_imu, until);
  epochs.flush();
  return out;
}

const RunOutcome& clean() {
  static const RunOutcome o = run(nullptr);
  return o;
}

double error_at(const nu::Estimate& e, double original_t) {
  return (e.position - eval::position_at(drive().drive.truth, original_t).head<2>()).norm();
}

std::size_t region_of(double t) { return static_cast<std::size_t>(eval::region_at(drive().drive.truth, t)); }

/// 95th percentile of the clean run's errors per true region (outdoor, transition, indoor):
/// centimetres among the anchors in the garage, metres on the approach outside it.
const std::array<double, 3>& clean_p95() {
  static const std::array<double, 3> p = [] {
    std::array<std::vector<double>, 3> by;
    for (const auto& x : clean().track.estimates) by[region_of(x.t)].push_back(error_at(x, x.t));
    std::array<double, 3> q{};
    for (std::size_t r = 0; r < 3; ++r) q[r] = by[r].empty() ? 0.0 : eval::percentile(by[r], 95.0);
    return q;
  }();
  return p;
}

Fault window(std::string n, FaultKind k, double begin, double length) {
  return fault_window(std::move(n), k, StreamId::uwb, begin, length);
}

/// Ranges of anchor `id` (any if < 0) the gate refused in [a, b) of a track.
std::size_t gated_in(const nu::Track& tr, double a, double b, int id) {
  return static_cast<std::size_t>(std::count_if(tr.ranges.begin(), tr.ranges.end(), [&](const nu::RangeRecord& r) {
    return r.range.t >= a && r.range.t < b && (id < 0 || r.range.anchor_id == id) && r.attached && r.status.outcome == Outcome::gated;
  }));
}
int first_anchor_after(double t) {
  for (const auto& r : ranges())
    if (r.t >= t) return r.anchor_id;
  return -1;
}

/// Ranges of anchor `id` (any if < 0) stamped in [a, b).
std::size_t ranges_in(double a, double b, int id = -1) {
  return static_cast<std::size_t>(std::count_if(ranges().begin(), ranges().end(), [&](const messages::UwbRange& r) {
    return r.t >= a && r.t < b && (id < 0 || r.anchor_id == id);
  }));
}
/// The last stamp before t.
double last_before(double t) {
  double last = -std::numeric_limits<double>::infinity();
  for (const auto& r : ranges())
    if (r.t < t) last = r.t;
  return last;
}

void check_fault(const Fault& f) {
  SCOPED_TRACE(f.name);
  const RunOutcome& base = clean();
  const RunOutcome out = run(&f);
  EXPECT_TRUE(out.checks.clean()) << "non-finite " << out.checks.non_finite << ", asymmetric " << out.checks.asymmetric
                                  << ", not PD " << out.checks.not_pd << " of " << out.checks.checked;
  const std::size_t n = ranges_in(f.begin, f.end);
  const io::StreamReport& rep = out.replay.streams[0];
  std::string evidence;
  if (const auto replayed = replay_evidence(f, rep, n)) {
    evidence = *replayed;
  } else if (f.kind == FaultKind::nan_value || f.kind == FaultKind::inf_value) {
    const std::size_t refused = out.track.ranges_invalid - base.track.ranges_invalid;
    EXPECT_EQ(refused, n);
    EXPECT_EQ(out.replay.dropped(), 0u);
    evidence = format("%zu of %zu refused by the EKF (Track::ranges_invalid)", refused, n);
  } else if (f.kind == FaultKind::clock_jump && f.clock_jump_s < 0.0) {
    // The ranges after the jump stamped (2 s early) before the last one delivered.
    EXPECT_EQ(rep.backwards, ranges_in(f.begin, last_before(f.begin) - f.clock_jump_s));
    evidence = format("%zu backwards dropped (replay report)", rep.backwards);
  } else if (f.kind == FaultKind::clock_jump) {
    // One stream on one clock: a late clock is a 5 s gap, which the motion model bridges.
    EXPECT_EQ(out.replay.dropped(), 0u);
    evidence = format("none possible (one stream, one clock): a 5 s gap, %zu dropped", out.replay.dropped());
  } else if (f.kind == FaultKind::wrong_anchor) {
    const int id = first_anchor_after(f.begin);
    const std::size_t g = gated_in(out.track, f.begin, f.end, id) - gated_in(base.track, f.begin, f.end, id);
    EXPECT_GE(g, 1u);
    evidence = format("%zu more of anchor %d's %zu ranges gated, %zu restarts", g, id, ranges_in(f.begin, f.end, id),
                      out.track.restarts - base.track.restarts);
  }

  // Recovery.
  const auto& p95 = clean_p95();
  Recovery rec{f, recovery_s, window_s};
  const auto& ce = base.track.estimates;
  for (const auto& e : out.track.estimates) {
    const double t = f.original(e.t);
    const double err = error_at(e, t);
    if (!rec.take(t, err)) continue;
    // The clean estimate nearest in time (epochs are 0.1 s apart; a clock jump shifts them).
    const auto j = std::lower_bound(ce.begin(), ce.end(), t, [](const nu::Estimate& x, double v) { return x.t < v; });
    ASSERT_NE(j, ce.end());
    rec.check(t, err, 2.0 * std::max(p95[region_of(t)], error_at(*j, j->t)));
  }
  EXPECT_GE(rec.checked, static_cast<std::size_t>(window_s * 5.0));  // 10 Hz epochs, half of them at least
  std::printf("| %s | NLOS UWB (EKF) | %s | %.2f | %.2f | %.2f |\n", f.name.c_str(), evidence.c_str(), rec.during, rec.worst,
              rec.share);
}

TEST(FaultInjectionUwb, CleanRunIsClean) {
  const RunOutcome& o = clean();
  EXPECT_TRUE(o.checks.clean());
  EXPECT_EQ(o.replay.dropped(), 0u);
  ASSERT_FALSE(o.track.estimates.empty());
  const auto& p = clean_p95();
  std::printf("clean NLOS UWB (EKF): %zu estimates, error p95 outdoor %.2f m, transition %.2f m, indoor %.2f m; faults at %.1f s\n",
              o.track.estimates.size(), p[0], p[1], p[2], fault_time());
}

TEST(FaultInjectionUwb, Faults) {
  const double t = fault_time();
  std::vector<Fault> v{
      window("UWB NaN 5 s", FaultKind::nan_value, t, 5.0),
      window("UWB Inf 5 s", FaultKind::inf_value, t, 5.0),
      window("UWB NaN stamp 5 s", FaultKind::nan_stamp, t, 5.0),
      window("UWB dropout 10 s", FaultKind::dropout, t, 10.0),
      window("UWB duplicated 10 s", FaultKind::duplicate, t, 10.0),
      window("UWB out of order 10 s", FaultKind::out_of_order, t, 10.0),
      window("UWB anchor 5 m off 30 s", FaultKind::wrong_anchor, t, 30.0),
  };
  Fault ahead = window("clock +5 s", FaultKind::clock_jump, t + 0.05, 0.0);
  ahead.stream = StreamId::all;
  Fault back = ahead;
  back.name = "clock -2 s";
  back.clock_jump_s = -2.0;
  v.push_back(ahead);
  v.push_back(back);
  for (const Fault& f : v) check_fault(f);
}

}  // namespace fault_injection_uwb

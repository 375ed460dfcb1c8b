// The replay (io/replay.hpp) against propagation by hand. A handler integrates x += u * dt with
// the held IMU sample and records every call; the tests compute what it must have seen from the
// IMU samples alone (interval by interval), and the order of the calls by sorting the messages
// themselves. Streams at 100 Hz (IMU), 10 Hz (on IMU stamps), 4 Hz and 1 Hz (3 ms after an IMU
// stamp, so between two samples; the 1 Hz stamps coincide with 4 Hz ones).
#include <gtest/gtest.h>

#include <ctxfuse/io/replay.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <limits>
#include <span>
#include <tuple>
#include <vector>

namespace {

namespace io = ctxfuse::io;

namespace messages = ctxfuse::messages;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kOffset = 0.003;  // of the 4 Hz and 1 Hz stamps from the IMU grid

// One handler call. kind: 'p' propagate (t: the held sample's stamp, value: dt, x after it),
// 'i' IMU sample, 'g' fix, 's' speed, 'm' mag, 'u' range (value: a payload, x when called).
struct Event {
  char kind = 0;
  double t = 0.0;
  double value = 0.0;
  double x = 0.0;
  bool operator==(const Event&) const = default;
};

struct Integrator {
  double x = 0.0;
  std::vector<Event> events;
  void propagate(const messages::ImuSample& u, double dt) {
    x += u.gyro.x() * dt;
    events.push_back({'p', u.t, dt, x});
  }
  void on(const messages::ImuSample& u) { events.push_back({'i', u.t, u.gyro.x(), x}); }
  void on(const messages::GnssFix& m) { events.push_back({'g', m.t, m.position.x(), x}); }
  void on(const messages::SpeedSample& m) { events.push_back({'s', m.t, m.speed_mps, x}); }
  void on(const messages::MagSample& m) { events.push_back({'m', m.t, m.field_ut.x(), x}); }
  void on(const messages::UwbRange& m) { events.push_back({'u', m.t, m.range_m + 1000.0 * m.anchor_id, x}); }

  std::vector<Event> calls_except_propagate() const {
    std::vector<Event> out;
    std::copy_if(events.begin(), events.end(), std::back_inserter(out), [](const Event& e) { return e.kind != 'p'; });
    return out;
  }
};

template <class T>
std::span<const T> sp(const std::vector<T>& v) {
  return {v.data(), v.size()};
}

// Message k of a stream, for k in [first, last], filled in by set(message, k).
template <class M, class Set>
std::vector<M> stream(int first, int last, Set set) {
  std::vector<M> v;
  for (int k = first; k <= last; ++k) set(v.emplace_back(), k);
  return v;
}
// Rates that change from sample to sample, so that holding the wrong sample shows.
std::vector<messages::ImuSample> imu_100hz(int last = 300, int first = 0) {
  return stream<messages::ImuSample>(first, last, [](auto& s, int k) { s.t = k / 100.0; s.gyro.x() = 1.0 + 0.5 * (k % 7); });
}
std::vector<messages::GnssFix> fixes_10hz(int last = 30) {
  return stream<messages::GnssFix>(0, last, [](auto& f, int k) { f.t = k / 10.0; f.position.x() = k; });
}
std::vector<messages::SpeedSample> speed_4hz(int last = 11) {
  return stream<messages::SpeedSample>(0, last, [](auto& s, int k) { s.t = kOffset + k / 4.0; s.speed_mps = k; });
}
std::vector<messages::MagSample> mag_1hz(int last = 2) {
  return stream<messages::MagSample>(0, last, [](auto& m, int k) { m.t = kOffset + k; m.field_ut.x() = k; });
}
// Three anchors per stamp (anchor 1, 2, 3 for k % 3 = 0, 1, 2), 5 Hz, 5 ms after the IMU grid.
std::vector<messages::UwbRange> ranges_5hz(int last = 14) {
  return stream<messages::UwbRange>(0, 3 * last + 2, [](auto& r, int k) {
    r.t = 0.005 + (k / 3) / 5.0;
    r.anchor_id = 1 + k % 3;
    r.range_m = 10.0 + k / 3;
  });
}

// x at time t by hand: each sample's rate held from its stamp to the next sample's, summed.
double integral_to(const std::vector<messages::ImuSample>& imu, double t) {
  double x = 0.0;
  for (std::size_t k = 0; k + 1 < imu.size() && imu[k].t < t; ++k)
    x += imu[k].gyro.x() * (std::min(t, imu[k + 1].t) - imu[k].t);
  return x;
}

// The calls a replay must make apart from propagation: every message sorted by stamp, an IMU
// sample before measurements of its stamp, measurements of one stamp in stream order (rank).
struct Expected {
  std::vector<std::tuple<double, int, Event>> items;
  void add(int rank, char kind, double t, double value) { items.push_back({t, rank, Event{kind, t, value, 0.0}}); }
  std::vector<Event> in_order() {
    std::stable_sort(items.begin(), items.end(),
                     [](const auto& a, const auto& b) { return std::tie(std::get<0>(a), std::get<1>(a)) < std::tie(std::get<0>(b), std::get<1>(b)); });
    std::vector<Event> out;
    for (const auto& i : items) out.push_back(std::get<2>(i));
    return out;
  }
};

// A stream's report as {delivered, non_finite, backwards, repeated, duplicate, beyond_imu,
// tampered}, so that one comparison checks every count.
using Counts = std::array<std::size_t, 7>;
Counts counts(const io::StreamReport& r) {
  return {r.delivered, r.non_finite, r.backwards, r.repeated, r.duplicate, r.beyond_imu, r.tampered};
}

void expect_same_calls(const std::vector<Event>& got, std::vector<Event> want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].kind, want[i].kind) << "call " << i << " at t=" << want[i].t;
    EXPECT_EQ(got[i].t, want[i].t) << "call " << i;
    EXPECT_EQ(got[i].value, want[i].value) << "call " << i;
  }
}

}  // namespace

TEST(Replay, MeasurementsBetweenImuSamplesAreAppliedAtTheirOwnTime) {
  const auto imu = imu_100hz();
  const auto fixes = fixes_10hz();
  const auto speed = speed_4hz();
  const auto mag = mag_1hz();
  Integrator h;
  const auto report = io::replay(h, sp(imu), sp(fixes), sp(speed), sp(mag));

  Expected want;
  for (const auto& s : imu) want.add(0, 'i', s.t, s.gyro.x());
  for (const auto& f : fixes) want.add(1, 'g', f.t, f.position.x());
  for (const auto& s : speed) want.add(2, 's', s.t, s.speed_mps);
  for (const auto& m : mag) want.add(3, 'm', m.t, m.field_ut.x());
  expect_same_calls(h.calls_except_propagate(), want.in_order());

  // Each call saw the state propagated by hand to its own stamp.
  int between = 0;
  for (const auto& e : h.calls_except_propagate()) {
    const double by_hand = integral_to(imu, e.t);
    EXPECT_NEAR(e.x, by_hand, 1e-12) << e.kind << " at t=" << e.t;
    if (e.kind == 's' || e.kind == 'm') {
      // The test can tell: at the IMU sample before it the state differs by u * 3 ms.
      EXPECT_GT(std::abs(by_hand - integral_to(imu, e.t - kOffset)), 2e-3);
      ++between;
    }
  }
  EXPECT_EQ(between, 15);

  // Every interval is propagated with its own sample, in pieces that add up to the interval;
  // split once at each 4 Hz stamp (the 1 Hz ones share them, the 10 Hz ones are on the grid).
  std::size_t pieces = 0;
  for (std::size_t k = 0; k + 1 < imu.size(); ++k) {
    double sum = 0.0;
    std::size_t n = 0;
    for (const auto& e : h.events)
      if (e.kind == 'p' && e.t == imu[k].t) {
        EXPECT_GT(e.value, 0.0);
        sum += e.value;
        ++n;
      }
    EXPECT_NEAR(sum, imu[k + 1].t - imu[k].t, 1e-15) << "interval " << k;
    const bool split = std::any_of(speed.begin(), speed.end(), [&](const auto& s) { return s.t > imu[k].t && s.t < imu[k + 1].t; });
    EXPECT_EQ(n, split ? 2u : 1u) << "interval " << k;
    pieces += n;
  }
  EXPECT_EQ(pieces, 300u + 12u);
  EXPECT_EQ(report.propagations, pieces);
  EXPECT_NEAR(h.x, integral_to(imu, 3.0), 1e-12);

  EXPECT_EQ(counts(report.imu), (Counts{301, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(counts(report.streams[0]), (Counts{31, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(counts(report.streams[1]), (Counts{12, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(counts(report.streams[2]), (Counts{3, 0, 0, 0, 0, 0, 0}));
}

TEST(Replay, TiesGoToTheImuSampleThenToTheStreamListedFirst) {
  const auto imu = imu_100hz(100);
  const auto fixes = fixes_10hz(10);
  const auto speed = speed_4hz(3);
  const auto mag = mag_1hz(0);
  for (const bool mag_first : {true, false}) {
    Integrator h;
    if (mag_first)
      (void)io::replay(h, sp(imu), sp(mag), sp(speed));
    else
      (void)io::replay(h, sp(imu), sp(speed), sp(mag));
    const auto calls = h.calls_except_propagate();
    const auto at = [&](char kind, double t) {
      return std::find_if(calls.begin(), calls.end(), [&](const Event& e) { return e.kind == kind && e.t == t; }) - calls.begin();
    };
    EXPECT_EQ(at('m', kOffset) < at('s', kOffset), mag_first);
  }
  // A fix on an IMU stamp comes after that sample, and the sample held from then on is the new one.
  Integrator h;
  (void)io::replay(h, sp(imu), sp(fixes));
  const auto calls = h.calls_except_propagate();
  for (std::size_t i = 0; i < calls.size(); ++i)
    if (calls[i].kind == 'g') {
      ASSERT_GT(i, 0u);
      EXPECT_EQ(calls[i - 1].kind, 'i');
      EXPECT_EQ(calls[i - 1].t, calls[i].t);
    }
  const auto after_fix = std::find_if(h.events.begin(), h.events.end(), [](const Event& e) { return e.kind == 'g' && e.t == 0.5; });
  ASSERT_NE(after_fix, h.events.end());
  EXPECT_EQ(std::next(after_fix)->kind, 'p');
  EXPECT_EQ(std::next(after_fix)->t, 0.5);  // propagated with the sample stamped 0.5, not 0.49
  // Several anchors with one stamp come in their order in the stream.
  const auto ranges = ranges_5hz(1);
  Integrator u;
  const auto report = io::replay(u, sp(imu), sp(ranges));
  const auto range_calls = u.calls_except_propagate();
  std::vector<double> seen;
  for (const auto& e : range_calls)
    if (e.kind == 'u') seen.push_back(e.value);
  EXPECT_EQ(seen, (std::vector<double>{1010, 2010, 3010, 1011, 2011, 3011}));
  EXPECT_EQ(report.streams[0].delivered, 6u);
  EXPECT_EQ(report.streams[0].dropped(), 0u);
}

TEST(Replay, BadStampsAreCountedPerStreamDroppedAndChangeNothing) {
  const auto imu = imu_100hz();
  const auto fixes = fixes_10hz();
  const auto speed = speed_4hz();
  const auto ranges = ranges_5hz();
  Integrator clean;
  const auto clean_report = io::replay(clean, sp(imu), sp(fixes), sp(speed), sp(ranges));
  EXPECT_EQ(clean_report.dropped(), 0u);  // three anchors sharing each stamp all pass
  EXPECT_EQ(clean_report.streams[2].delivered, 45u);

  // Every bad message carries a value that would show if it were used.
  auto bad_imu = imu;
  const auto imu_at = [](double t) { return messages::ImuSample{t, Eigen::Vector3d(1e6, 0.0, 0.0), {}, false}; };
  bad_imu.insert(bad_imu.begin() + 151, imu_at(1.5));   // repeated (after the sample at 1.5)
  bad_imu.insert(bad_imu.begin() + 101, imu_at(0.95));  // backwards (after 1.0)
  bad_imu.insert(bad_imu.begin() + 51, imu_at(kNaN));   // non-finite
  auto bad_fixes = fixes;
  const auto fix_at = [](double t) { messages::GnssFix f; f.t = t; f.position.x() = 999.0; return f; };
  bad_fixes.insert(bad_fixes.begin() + 21, fix_at(kInf));
  bad_fixes.insert(bad_fixes.begin() + 16, fix_at(-kInf));
  bad_fixes.insert(bad_fixes.begin() + 11, fix_at(1.0));   // repeated, other values
  bad_fixes.insert(bad_fixes.begin() + 6, fix_at(0.45));   // backwards (after 0.5)
  bad_fixes.insert(bad_fixes.begin() + 1, fix_at(kNaN));
  bad_fixes.push_back(fix_at(1.0));                        // backwards, last message
  auto bad_speed = speed;
  bad_speed.insert(bad_speed.begin() + 5, bad_speed[4]);  // an exact copy: repeated
  auto bad_ranges = ranges;
  auto dup = ranges[4];  // anchor 2 of the second stamp, again with another range
  dup.range_m = 999.0;
  bad_ranges.insert(bad_ranges.begin() + 6, dup);             // after anchor 3 of that stamp
  bad_ranges.insert(bad_ranges.begin() + 5, ranges[3]);       // anchor 1 again, exact copy
  auto back = ranges[0];
  back.range_m = 999.0;
  bad_ranges.insert(bad_ranges.begin() + 9, back);            // backwards
  auto nan_range = ranges[9];
  nan_range.t = kNaN;
  bad_ranges.insert(bad_ranges.begin() + 12, nan_range);

  Integrator dirty;
  const auto r = io::replay(dirty, sp(bad_imu), sp(bad_fixes), sp(bad_speed), sp(bad_ranges));
  EXPECT_EQ(dirty.events, clean.events);  // exactly: the same calls, values and states
  EXPECT_EQ(dirty.x, clean.x);

  // {delivered, non_finite, backwards, repeated, duplicate, beyond_imu, tampered}
  EXPECT_EQ(counts(r.imu), (Counts{301, 1, 1, 1, 0, 0, 0}));
  EXPECT_EQ(counts(r.streams[0]), (Counts{31, 3, 2, 1, 0, 0, 0}));
  EXPECT_EQ(counts(r.streams[1]), (Counts{12, 0, 0, 1, 0, 0, 0}));
  EXPECT_EQ(counts(r.streams[2]), (Counts{45, 1, 1, 0, 2, 0, 0}));  // a shared stamp is no fault
  EXPECT_EQ(r.dropped(), 3u + 6u + 1u + 4u);
  EXPECT_EQ(r.propagations, clean_report.propagations);

  // Seventy anchors on one stamp: a duplicate of the last one is still seen.
  auto many = stream<messages::UwbRange>(1, 70, [](auto& m, int k) { m.t = 0.5; m.anchor_id = k; });
  many.push_back(many.back());
  Integrator crowded;
  EXPECT_EQ(counts(io::replay(crowded, sp(imu), sp(many)).streams[0]), (Counts{70, 0, 0, 0, 1, 0, 0}));
}

TEST(Replay, MeasurementsAfterTheLastImuSampleAreCountedNotDelivered) {
  const auto imu = imu_100hz(100);     // up to 1.0 s
  const auto fixes = fixes_10hz(15);   // up to 1.5 s: the one at 1.0 is still in reach
  const auto speed = speed_4hz(6);     // up to 1.503 s
  Integrator h;
  const auto r = io::replay(h, sp(imu), sp(fixes), sp(speed));
  EXPECT_EQ(counts(r.streams[0]), (Counts{11, 0, 0, 0, 0, 5, 0}));
  EXPECT_EQ(counts(r.streams[1]), (Counts{4, 0, 0, 0, 0, 3, 0}));
  EXPECT_EQ(r.dropped(), 8u);
  double propagated = 0.0;
  for (const auto& e : h.events) {
    if (e.kind == 'p') propagated += e.value;
    if (e.kind != 'p' && e.kind != 'i') {
      EXPECT_LE(e.t, 1.0);
    }
  }
  EXPECT_NEAR(propagated, 1.0, 1e-12);
  EXPECT_EQ(h.calls_except_propagate().back().kind, 'g');  // the fix at 1.0, after the sample at 1.0
}

TEST(Replay, MeasurementsBeforeTheFirstImuSampleAreDeliveredUnpropagated) {
  const auto imu = imu_100hz(100, 50);  // from 0.5 s
  const auto fixes = fixes_10hz(7);
  Integrator h;
  const auto r = io::replay(h, sp(imu), sp(fixes));
  EXPECT_EQ(r.streams[0].delivered, 8u);
  EXPECT_EQ(r.dropped(), 0u);
  for (const auto& e : h.calls_except_propagate())
    if (e.kind == 'g') {
      EXPECT_NEAR(e.x, integral_to(imu, e.t), 1e-12) << e.t;  // 0 up to 0.5 s
    }
  EXPECT_EQ(h.events.front().kind, 'g');
  EXPECT_EQ(h.events.front().x, 0.0);
}

namespace {
template <class... F>
struct Overload : F... {
  using F::operator()...;
};
template <class... F>
Overload(F...) -> Overload<F...>;
constexpr auto pass = [](auto&) { return true; };
}  // namespace

TEST(Replay, TamperHookDropsDelaysAndCorruptsThroughTheSameChecks) {
  const auto imu = imu_100hz();
  const auto fixes = fixes_10hz();
  const auto speed = speed_4hz();
  const auto mag = mag_1hz();
  const auto imu_before = imu;

  // Drop: every odd fix, as if they had never been recorded.
  auto even_fixes = fixes;
  std::erase_if(even_fixes, [](const messages::GnssFix& f) { return static_cast<int>(f.position.x()) % 2 == 1; });
  Integrator filtered, dropped;
  (void)io::replay(filtered, sp(imu), sp(even_fixes), sp(speed), sp(mag));
  auto drop = Overload{pass, [](messages::GnssFix& f) { return static_cast<int>(f.position.x()) % 2 == 0; }};
  auto r = io::replay_tampered(dropped, drop, sp(imu), sp(fixes), sp(speed), sp(mag));
  EXPECT_EQ(dropped.events, filtered.events);
  EXPECT_EQ(counts(r.streams[0]), (Counts{16, 0, 0, 0, 0, 0, 15}));
  EXPECT_EQ(r.dropped(), 15u);

  // Delay: the speed stamps 50 ms late; the state at each is the hand-propagated one there.
  auto late_speed = speed;
  for (auto& s : late_speed) s.t += 0.05;
  Integrator shifted, delayed;
  (void)io::replay(shifted, sp(imu), sp(fixes), sp(late_speed), sp(mag));
  auto delay = Overload{pass, [](messages::SpeedSample& s) { s.t += 0.05; return true; }};
  r = io::replay_tampered(delayed, delay, sp(imu), sp(fixes), sp(speed), sp(mag));
  EXPECT_EQ(delayed.events, shifted.events);
  EXPECT_EQ(r.dropped(), 0u);
  int seen = 0;
  for (const auto& e : delayed.events)
    if (e.kind == 's') {
      EXPECT_NEAR(e.x, integral_to(imu, speed[static_cast<std::size_t>(e.value)].t + 0.05), 1e-12);
      ++seen;
    }
  EXPECT_EQ(seen, 12);
  EXPECT_EQ(speed.front().t, kOffset);  // the recording itself is untouched

  // Corrupt: a gyro bias of 0.25 rad/s and a sign flip of the field.
  auto biased = imu;
  for (auto& s : biased) s.gyro.x() += 0.25;
  Integrator corrupted;
  auto corrupt = Overload{pass, [](messages::ImuSample& s) { s.gyro.x() += 0.25; return true; },
                          [](messages::MagSample& m) { m.field_ut.x() = -m.field_ut.x(); return true; }};
  r = io::replay_tampered(corrupted, corrupt, sp(imu), sp(fixes), sp(speed), sp(mag));
  EXPECT_EQ(r.dropped(), 0u);
  for (const auto& e : corrupted.events) {
    if (e.kind == 'p') continue;
    EXPECT_NEAR(e.x, integral_to(biased, e.t), 1e-12) << e.kind << " " << e.t;
    if (e.kind == 'm') {
      EXPECT_EQ(e.value, -std::round(e.t));
    }
  }
  EXPECT_EQ(imu[7].gyro.x(), imu_before[7].gyro.x());

  // A stamp the hook breaks is caught by the checks, as a recorded one would be.
  Integrator broken;
  auto nan_stamp = Overload{pass, [](messages::GnssFix& f) { f.t = f.position.x() == 3.0 ? kNaN : f.t; return true; }};
  const auto rb = io::replay_tampered(broken, nan_stamp, sp(imu), sp(fixes));
  EXPECT_EQ(counts(rb.streams[0]), (Counts{30, 1, 0, 0, 0, 0, 0}));  // non-finite, not tampered
}

namespace {
// A handler without on(ImuSample) (optional) that also counts propagations.
struct MeasurementsOnly {
  int propagations = 0;
  std::vector<Event> events;
  void propagate(const messages::ImuSample&, double) { ++propagations; }
  void on(const messages::GnssFix& m) { events.push_back({'g', m.t, m.position.x(), 0.0}); }
  void on(const messages::SpeedSample& m) { events.push_back({'s', m.t, m.speed_mps, 0.0}); }
  void on(const messages::MagSample& m) { events.push_back({'m', m.t, m.field_ut.x(), 0.0}); }
};
}  // namespace

TEST(Replay, WithoutImuMeasurementsComeInOrderAndNothingIsPropagated) {
  const auto fixes = fixes_10hz();
  const auto speed = speed_4hz();
  const auto mag = mag_1hz();
  MeasurementsOnly h;
  const auto r = io::replay(h, std::span<const messages::ImuSample>{}, sp(fixes), sp(speed), sp(mag));
  Expected want;
  for (const auto& f : fixes) want.add(1, 'g', f.t, f.position.x());
  for (const auto& s : speed) want.add(2, 's', s.t, s.speed_mps);
  for (const auto& m : mag) want.add(3, 'm', m.t, m.field_ut.x());
  expect_same_calls(h.events, want.in_order());
  EXPECT_EQ(h.propagations, 0);
  EXPECT_EQ(r.propagations, 0u);
  EXPECT_EQ(r.streams[0].delivered + r.streams[1].delivered + r.streams[2].delivered, 31u + 12u + 3u);
  EXPECT_EQ(r.dropped(), 0u);  // in particular nothing is beyond an IMU that is not there

  // The same handler with an IMU stream: on(ImuSample) is optional.
  const auto imu = imu_100hz();
  MeasurementsOnly with_imu;
  (void)io::replay(with_imu, sp(imu), sp(fixes), sp(speed), sp(mag));
  EXPECT_EQ(with_imu.propagations, 312);
  expect_same_calls(with_imu.events, want.in_order());
}

namespace {

// Increment samples (angle increments over the interval that ends at their stamp): over each
// interval the handler gets the mean rate of the sample that ends it, so x integrates exactly
// to the sum of the increments, and a measurement inside an interval sees that interval's
// rate times the time elapsed in it.
TEST(Replay, IncrementSamplesActOverTheIntervalThatEndsAtTheirStamp) {
  std::vector<messages::ImuSample> imu;
  const std::array<double, 5> stamps{0.0, 0.01, 0.02, 0.035, 0.05};  // irregular
  const std::array<double, 5> increments{9.0, 0.02, -0.01, 0.03, 0.045};  // the first is never used
  for (std::size_t k = 0; k < stamps.size(); ++k) {
    messages::ImuSample s;
    s.t = stamps[k];
    s.gyro.x() = increments[k];
    s.increments = true;
    imu.push_back(s);
  }
  std::vector<messages::GnssFix> fixes(1);
  fixes[0].t = 0.03;  // 2/3 of the way through (0.02, 0.035]
  Integrator h;
  const auto report = io::replay(h, sp(imu), sp(fixes));
  EXPECT_EQ(report.imu.delivered, 5u);
  EXPECT_NEAR(h.x, 0.02 - 0.01 + 0.03 + 0.045, 1e-15);
  // The fix saw the first two intervals whole and 2/3 of the third.
  const auto fix = std::find_if(h.events.begin(), h.events.end(), [](const Event& e) { return e.kind == 'g'; });
  ASSERT_NE(fix, h.events.end());
  EXPECT_NEAR(fix->x, 0.02 - 0.01 + 0.03 * (0.01 / 0.015), 1e-15);
  // Every propagation hands the handler rates, never increments.
  for (const auto& e : h.events) {
    if (e.kind == 'p') {
      EXPECT_GT(e.value, 0.0);
    }
  }
}

}  // namespace

// One time-ordered replay over any set of sensor streams: the merge that every pipeline runs
// on, whether the streams come from a recording or from the simulator.
//
//   replay(handler, imu, stream_0, stream_1, ...)
//   replay_tampered(handler, tamper, imu, stream_0, stream_1, ...)
//
// merges the streams by time stamp and calls the handler:
//   handler.propagate(u, dt)  the IMU rates u in force over the next dt > 0 seconds: a
//                             measurement between two IMU samples splits that interval
//                             (propagate to the measurement's time, update, propagate the rest),
//                             so no rate needs to divide another. Rate samples hold from their
//                             stamp to the next one's; an increment sample covers the interval
//                             that ends at its stamp, so over that interval u is its mean rate
//                             (increment / interval, `increments` false), and the first
//                             increment sample, whose interval is unknown, only starts the clock;
//   handler.on(u)             optional, for each IMU sample after the propagation to its time;
//   handler.on(m)             for each measurement m of stream k, at its time.
// Ties: an IMU sample comes before the measurements with its stamp (the state is propagated
// to a measurement's time before the measurement is used), and measurements with one stamp
// come in the order of the stream arguments (a pipeline lists its streams in the order in
// which it wants simultaneous measurements; e.g. ranges before the fix of the same epoch).
// Without an IMU stream (an empty span), nothing is propagated: the handler predicts with its
// own motion model from the measurement times. With one, measurements after the last IMU sample
// are not delivered (there is nothing to propagate them with) and are counted; measurements
// before the first IMU sample are delivered unpropagated (the state the handler starts from:
// a pipeline may start from the first fixes before the IMU runs).
//
// Stamps are checked per stream, never repaired: a non-finite stamp, one before the previous
// delivered stamp of its stream, or (for streams whose messages may not share a stamp) one
// equal to it (`repeated`), drops the message and counts it; in streams whose messages share
// stamps (UWB ranges of several anchors), the same measurement again (same anchor and stamp) is
// a `duplicate`. Nothing is reordered. The report says what was delivered and dropped, per
// stream.
//
// `tamper` is the fault-injection hook: before a message's stamp is checked it may drop the
// message or change any of its fields (delay its stamp, corrupt its values), so injected faults
// go through the same checks as recorded ones. NoTamper passes everything through untouched
// (and without a copy).
#pragma once

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "ctxfuse/messages/sensors.hpp"

namespace ctxfuse::io {

/// Whether several messages of this type may carry one stamp (ranges from several anchors,
/// satellites of one epoch); otherwise a stream's stamps must increase strictly.
template <class Msg>
inline constexpr bool kSharedStamps = false;
template <>
inline constexpr bool kSharedStamps<messages::UwbRange> = true;

/// Two messages of a shared-stamp stream that are the same measurement delivered twice (in
/// other streams the stamp alone identifies a measurement: an equal stamp is `repeated`).
template <class Msg>
bool same_measurement(const Msg& a, const Msg& b) {
  if constexpr (std::is_same_v<Msg, messages::UwbRange>)
    return a.t == b.t && a.anchor_id == b.anchor_id;
  else
    return a.t == b.t;
}

enum class StampProblem : std::uint8_t { none, non_finite, backwards, repeated, duplicate, beyond_imu, tampered };

struct StreamReport {
  std::size_t delivered = 0;
  std::size_t non_finite = 0;  // stamp NaN or infinite
  std::size_t backwards = 0;   // stamp before the previous delivered one of the stream
  std::size_t repeated = 0;    // stamp equal to the previous one where stamps may not be shared
  std::size_t duplicate = 0;   // the same measurement again where stamps may be shared
  std::size_t beyond_imu = 0;  // after the last IMU sample
  std::size_t tampered = 0;    // dropped by the tamper hook
  std::size_t dropped() const { return non_finite + backwards + repeated + duplicate + beyond_imu + tampered; }
  void count(StampProblem p) {
    switch (p) {
      case StampProblem::none: ++delivered; break;
      case StampProblem::non_finite: ++non_finite; break;
      case StampProblem::backwards: ++backwards; break;
      case StampProblem::repeated: ++repeated; break;
      case StampProblem::duplicate: ++duplicate; break;
      case StampProblem::beyond_imu: ++beyond_imu; break;
      case StampProblem::tampered: ++tampered; break;
    }
  }
};

/// imu: the IMU stream; streams[k]: the k-th measurement stream of the replay call.
template <std::size_t N>
struct ReplayReport {
  StreamReport imu;
  std::array<StreamReport, N> streams{};
  std::size_t propagations = 0;
  std::size_t dropped() const {
    std::size_t n = imu.dropped();
    for (const auto& s : streams) n += s.dropped();
    return n;
  }
};

/// Passes every message through unchanged.
struct NoTamper {};

namespace detail {

/// One stream's cursor: the next message that passed the tamper hook and the stamp checks.
template <class Msg>
class Cursor {
 public:
  explicit Cursor(std::span<const Msg> messages) : messages_(messages) {}

  /// Advances to the next deliverable message, counting the ones dropped on the way.
  template <class Tamper>
  void advance(Tamper& tamper, StreamReport& report) {
    head_ = nullptr;
    while (next_ < messages_.size()) {
      const Msg* m = &messages_[next_++];
      if constexpr (!std::is_same_v<Tamper, NoTamper>) {
        scratch_ = *m;
        if (!tamper(*scratch_)) {
          report.count(StampProblem::tampered);
          continue;
        }
        m = &*scratch_;
      }
      const StampProblem p = check(*m);
      if (p != StampProblem::none) {
        report.count(p);
        continue;
      }
      head_ = m;
      return;
    }
  }
  const Msg* head() const { return head_; }
  double time() const { return head_ ? head_->t : std::numeric_limits<double>::infinity(); }
  /// The head was delivered: it becomes the reference of the stamp checks.
  void accept() {
    last_t_ = head_->t;
    have_last_ = true;
    if constexpr (kSharedStamps<Msg>) recent_.push(*head_);
  }

 private:
  // Only the stamp of the previous message is kept (a copy of a satellite epoch would
  // allocate per message), and for shared-stamp streams the messages of that stamp.
  StampProblem check(const Msg& m) const {
    if (!std::isfinite(m.t)) return StampProblem::non_finite;
    if (!have_last_) return StampProblem::none;
    if (m.t < last_t_) return StampProblem::backwards;
    if (m.t == last_t_) {
      if constexpr (kSharedStamps<Msg>)
        return recent_.contains(m) ? StampProblem::duplicate : StampProblem::none;
      else
        return StampProblem::repeated;
    }
    return StampProblem::none;
  }

  /// The delivered messages of the current stamp (a few anchors), for the duplicate check.
  /// Cleared, not freed, at each new stamp: it allocates only when a stamp has more messages
  /// than any before it, and it has no capacity past which a duplicate would go unseen.
  struct Recent {
    std::vector<Msg> items;
    void push(const Msg& m) {
      if (!items.empty() && items.front().t != m.t) items.clear();
      items.push_back(m);
    }
    bool contains(const Msg& m) const {
      for (const auto& x : items)
        if (same_measurement(x, m)) return true;
      return false;
    }
  };

  std::span<const Msg> messages_;
  std::size_t next_ = 0;
  const Msg* head_ = nullptr;
  double last_t_ = 0.0;
  bool have_last_ = false;
  std::optional<Msg> scratch_;
  [[no_unique_address]] std::conditional_t<kSharedStamps<Msg>, Recent, std::tuple<>> recent_{};
};

}  // namespace detail

template <class Handler, class Tamper, class... Msgs>
ReplayReport<sizeof...(Msgs)> replay_tampered(Handler& handler, Tamper tamper, std::span<const messages::ImuSample> imu,
                                              std::span<const Msgs>... streams) {
  constexpr std::size_t N = sizeof...(Msgs);
  ReplayReport<N> report;
  detail::Cursor<messages::ImuSample> imu_cursor(imu);
  std::tuple<detail::Cursor<Msgs>...> cursors{detail::Cursor<Msgs>(streams)...};
  imu_cursor.advance(tamper, report.imu);
  [&]<std::size_t... K>(std::index_sequence<K...>) {
    (std::get<K>(cursors).advance(tamper, report.streams[K]), ...);
  }(std::make_index_sequence<N>{});

  const bool have_imu = !imu.empty();
  std::optional<messages::ImuSample> held;  // the IMU sample in force
  double now = -std::numeric_limits<double>::infinity();
  auto propagate_to = [&](double t) {
    if (held && t > now) {
      handler.propagate(*held, t - now);
      ++report.propagations;
    }
    if (t > now) now = t;
  };

  while (true) {
    // The earliest measurement head; ties go to the stream listed first.
    double t_meas = std::numeric_limits<double>::infinity();
    std::size_t k_meas = N;
    [&]<std::size_t... K>(std::index_sequence<K...>) {
      (
          [&] {
            if (std::get<K>(cursors).time() < t_meas) {
              t_meas = std::get<K>(cursors).time();
              k_meas = K;
            }
          }(),
          ...);
    }(std::make_index_sequence<N>{});
    const double t_imu = imu_cursor.time();
    if (k_meas == N && !imu_cursor.head()) break;

    if (imu_cursor.head() && t_imu <= t_meas) {
      propagate_to(t_imu);
      const messages::ImuSample sample = *imu_cursor.head();
      imu_cursor.accept();
      ++report.imu.delivered;
      if constexpr (requires { handler.on(sample); }) handler.on(sample);
      imu_cursor.advance(tamper, report.imu);
      held = sample;
      // Increments: the next sample's mean rate is what acts until its stamp.
      if (const messages::ImuSample* next = imu_cursor.head(); next && next->increments) {
        const double dt = next->t - sample.t;
        held = messages::ImuSample{sample.t, next->gyro / dt, next->accel / dt, false};
      } else if (sample.increments) {
        held.reset();  // the last increment sample: nothing acts after it
      }
      continue;
    }
    // A measurement, before the next IMU sample (or with no IMU sample left).
    const bool after_imu = have_imu && !imu_cursor.head();
    [&]<std::size_t... K>(std::index_sequence<K...>) {
      (
          [&] {
            if (K != k_meas) return;
            auto& c = std::get<K>(cursors);
            // Past the last IMU sample there is nothing to propagate with; a measurement at the
            // last sample's own time is still in reach.
            if (after_imu && c.time() > now) {
              report.streams[K].count(StampProblem::beyond_imu);
              c.advance(tamper, report.streams[K]);
              return;
            }
            propagate_to(c.time());
            handler.on(*c.head());
            c.accept();
            ++report.streams[K].delivered;
            c.advance(tamper, report.streams[K]);
          }(),
          ...);
    }(std::make_index_sequence<N>{});
  }
  return report;
}

/// Without fault injection.
template <class Handler, class... Msgs>
ReplayReport<sizeof...(Msgs)> replay(Handler& handler, std::span<const messages::ImuSample> imu, std::span<const Msgs>... streams) {
  return replay_tampered(handler, NoTamper{}, imu, streams...);
}

}  // namespace ctxfuse::io

// The generic part of fault injection through the replay's tamper hook (io/replay.hpp), for
// every pipeline's fault tests: a Fault says what happens to which stream over which stretch of
// the log's clock, FaultTamper is the hook that does it, BeliefChecks the checks of a belief
// after a step (finite, covariance symmetric and positive definite), replay_evidence and
// Recovery the evidence and recovery checks the tests share, simulated_drive the drive of the
// region and UWB pipelines' tests.
#pragma once

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/io/replay.hpp"
#include "ctxfuse/sim/scenarios.hpp"
#include "ctxfuse/sim/streams.hpp"

namespace ctxfuse::reliability {

enum class StreamId { imu, speed, uwb, gnss, sat_epochs, all };
enum class FaultKind { nan_value, inf_value, nan_stamp, gnss_jump, dropout, duplicate, out_of_order, clock_jump, wrong_anchor };

template <class Msg>
constexpr StreamId stream_of() {
  if constexpr (std::is_same_v<Msg, messages::ImuSample>) return StreamId::imu;
  else if constexpr (std::is_same_v<Msg, messages::SpeedSample>) return StreamId::speed;
  else if constexpr (std::is_same_v<Msg, messages::UwbRange>) return StreamId::uwb;
  else if constexpr (std::is_same_v<Msg, messages::GnssFix>) return StreamId::gnss;
  else return StreamId::sat_epochs;
}

/// One fault over the messages of `stream` stamped in [begin, end) on the log's clock.
///   nan_value / inf_value: the values the estimators read become NaN / +Inf (IMU rates,
///     speed, range, fix position);
///   nan_stamp: the stamp becomes NaN;  gnss_jump: the fix moves `jump_m` east;
///   dropout: the messages are lost;
///   duplicate: every second message is replaced by a copy of the one before it (the same
///     measurement twice, the real one lost);
///   out_of_order: every second message is stamped `reorder_s` before the one before it;
///   clock_jump: from `begin` on every stream's stamps are `clock_jump_s` late (end unused);
///   wrong_anchor: ranges from the first anchor heard after `begin` carry an anchor position
///     `anchor_error_m` east of the true one.
struct Fault {
  std::string name;
  FaultKind kind = FaultKind::dropout;
  StreamId stream = StreamId::all;
  double begin = 0.0, end = 0.0;
  double jump_m = 100.0, clock_jump_s = 5.0, anchor_error_m = 5.0, reorder_s = 0.5;

  /// When the fault is over (on the log's clock): the clock jump never ends, so its "end" is
  /// the jump itself.
  double over() const { return kind == FaultKind::clock_jump ? begin : end; }
  /// The stamp the replay saw for a message originally stamped t.
  double stamped(double t) const { return kind == FaultKind::clock_jump && t >= begin ? t + clock_jump_s : t; }
  /// The original time of a replayed stamp (inverse of stamped()). A clock jumped back stamps
  /// its first messages before the jump (`begin`): a stamp before `begin` is taken as one from
  /// before the jump.
  double original(double t) const {
    return kind == FaultKind::clock_jump && t >= begin + std::max(0.0, clock_jump_s) ? t - clock_jump_s : t;
  }
};

/// A fault of `kind` on stream `s` over [begin, begin + length).
inline Fault fault_window(std::string name, FaultKind kind, StreamId s, double begin, double length) {
  Fault f;
  f.name = std::move(name);
  f.kind = kind;
  f.stream = s;
  f.begin = begin;
  f.end = begin + length;
  return f;
}

/// The tamper hook for one Fault (copied into the replay; keeps per-stream memory).
class FaultTamper {
 public:
  explicit FaultTamper(const Fault& f) : f_(f) {}

  template <class Msg>
  bool operator()(Msg& m) {
    const double t = m.t;
    auto& mem = memory<Msg>();
    const bool hit = (f_.stream == StreamId::all || f_.stream == stream_of<Msg>()) && t >= f_.begin && t < f_.end;
    const std::optional<Msg> previous = mem.previous;
    mem.previous = m;
    switch (f_.kind) {
      case FaultKind::clock_jump: m.t = f_.stamped(t); return true;
      case FaultKind::nan_value:
        if (hit) corrupt(m, std::numeric_limits<double>::quiet_NaN());
        return true;
      case FaultKind::inf_value:
        if (hit) corrupt(m, std::numeric_limits<double>::infinity());
        return true;
      case FaultKind::nan_stamp:
        if (hit) m.t = std::numeric_limits<double>::quiet_NaN();
        return true;
      case FaultKind::gnss_jump:
        if constexpr (std::is_same_v<Msg, messages::GnssFix>)
          if (hit) m.position.x() += f_.jump_m;
        return true;
      case FaultKind::dropout: return !hit;
      case FaultKind::duplicate:
        if (hit && previous && (++mem.hits % 2 == 0)) m = *previous;
        return true;
      case FaultKind::out_of_order:
        if (hit && previous && (++mem.hits % 2 == 0)) m.t = previous->t - f_.reorder_s;
        return true;
      case FaultKind::wrong_anchor:
        if constexpr (std::is_same_v<Msg, messages::UwbRange>) {
          if (hit && anchor_ < 0) anchor_ = m.anchor_id;
          if (hit && m.anchor_id == anchor_) m.anchor_position.x() += f_.anchor_error_m;
        }
        return true;
    }
    return true;
  }

 private:
  template <class Msg>
  struct Memory {
    std::optional<Msg> previous;
    int hits = 0;
  };
  template <class Msg>
  Memory<Msg>& memory() {
    if constexpr (std::is_same_v<Msg, messages::ImuSample>) return imu_;
    else if constexpr (std::is_same_v<Msg, messages::SpeedSample>) return speed_;
    else if constexpr (std::is_same_v<Msg, messages::UwbRange>) return uwb_;
    else if constexpr (std::is_same_v<Msg, messages::GnssFix>) return gnss_;
    else return epochs_;
  }
  template <class Msg>
  static void corrupt(Msg& m, double bad) {
    if constexpr (std::is_same_v<Msg, messages::ImuSample>) {
      m.gyro.z() = bad;
      m.accel.x() = bad;
    } else if constexpr (std::is_same_v<Msg, messages::SpeedSample>) {
      m.speed_mps = bad;
    } else if constexpr (std::is_same_v<Msg, messages::UwbRange>) {
      m.range_m = bad;
    } else if constexpr (std::is_same_v<Msg, messages::GnssFix>) {
      m.position.x() = bad;
    } else {
      m.t = bad;  // a receiver epoch carries nothing else the estimators read
    }
  }

  Fault f_;
  int anchor_ = -1;
  Memory<messages::ImuSample> imu_;
  Memory<messages::SpeedSample> speed_;
  Memory<messages::UwbRange> uwb_;
  Memory<messages::GnssFix> gnss_;
  Memory<messages::SatEpoch> epochs_;
};

/// Messages of stream `s` (not `all`) in `log` stamped in [a, b).
inline std::size_t messages_in(const messages::SensorLog& log, StreamId s, double a, double b) {
  auto count = [&](const auto& v) {
    return static_cast<std::size_t>(std::count_if(v.begin(), v.end(), [&](const auto& m) { return m.t >= a && m.t < b; }));
  };
  switch (s) {
    case StreamId::imu: return count(log.imu);
    case StreamId::speed: return count(log.speed);
    case StreamId::uwb: return count(log.uwb);
    case StreamId::gnss: return count(log.gnss);
    case StreamId::sat_epochs: return count(log.sat_epochs);
    case StreamId::all: break;
  }
  return 0;
}

/// What the checks after every step found.
struct BeliefChecks {
  std::size_t checked = 0;
  std::size_t non_finite = 0;       // a mean or covariance entry NaN or infinite
  std::size_t asymmetric = 0;       // |P - P'| above 1e-12 of max |P|
  std::size_t not_pd = 0;           // Cholesky of P failed
  template <int N>
  void check(const Gaussian<N>& b) {
    check(b.mean.allFinite(), b.cov);
  }
  /// A belief whose mean is not a vector (an error-state filter's nominal state): whether its
  /// mean is finite, and its covariance.
  template <int N>
  void check(bool mean_finite, const SquareMatrix<N>& cov) {
    ++checked;
    if (!mean_finite || !cov.allFinite()) {
      ++non_finite;
      return;
    }
    const double scale = cov.cwiseAbs().maxCoeff();
    if ((cov - cov.transpose()).cwiseAbs().maxCoeff() > 1e-12 * scale) ++asymmetric;
    if (Eigen::LLT<SquareMatrix<N>>(cov).info() != Eigen::Success) ++not_pd;
  }
  void check_position(const Eigen::Vector2d& p) {
    ++checked;
    if (!p.allFinite()) ++non_finite;
  }
  bool clean() const { return checked > 0 && non_finite == 0 && asymmetric == 0 && not_pd == 0; }
};

/// The messages of `v` stamped before `t` (a stream is in time order).
template <class Msg>
std::span<const Msg> before(const std::vector<Msg>& v, double t) {
  const auto end = std::partition_point(v.begin(), v.end(), [&](const Msg& m) { return m.t < t; });
  return {v.data(), static_cast<std::size_t>(end - v.begin())};
}

/// printf into a string (a fault table's evidence column).
#if defined(__GNUC__)
__attribute__((format(printf, 1, 2)))
#endif
inline std::string format(const char* fmt, ...) {
  char buf[160];
  std::va_list args;
  va_start(args, fmt);
  std::vsnprintf(buf, sizeof buf, fmt, args);
  va_end(args);
  return buf;
}

/// Whether the messages of stream `s` may share a stamp (io::kSharedStamps): a copy of one is
/// then counted as a `duplicate`, otherwise as `repeated`.
inline bool shares_stamps(StreamId s) {
  switch (s) {
    case StreamId::imu: return io::kSharedStamps<messages::ImuSample>;
    case StreamId::speed: return io::kSharedStamps<messages::SpeedSample>;
    case StreamId::uwb: return io::kSharedStamps<messages::UwbRange>;
    case StreamId::gnss: return io::kSharedStamps<messages::GnssFix>;
    case StreamId::sat_epochs: return io::kSharedStamps<messages::SatEpoch>;
    case StreamId::all: break;
  }
  return false;
}

/// The evidence of a fault the replay drops itself (a NaN stamp, a dropout, a duplicate, out of
/// order) in `rep`, the replay report of the faulted stream: every touched message counted (`n`
/// the stream's messages in the fault's window; a duplicate or out-of-order fault touches every
/// second one). Returns the table's evidence, or nothing for the faults the replay passes on.
inline std::optional<std::string> replay_evidence(const Fault& f, const io::StreamReport& rep, std::size_t n) {
  switch (f.kind) {
    case FaultKind::nan_stamp:
      EXPECT_EQ(rep.non_finite, n);
      return format("%zu non-finite stamps dropped (replay report)", rep.non_finite);
    case FaultKind::dropout:
      EXPECT_EQ(rep.tampered, n);
      return format("%zu dropped (replay report)", rep.tampered);
    case FaultKind::duplicate: {
      const bool shared = shares_stamps(f.stream);
      const std::size_t copies = shared ? rep.duplicate : rep.repeated;
      EXPECT_EQ(rep.repeated + rep.duplicate, n / 2);
      return format("%zu %s dropped (replay report)", copies, shared ? "duplicate" : "repeated");
    }
    case FaultKind::out_of_order:
      EXPECT_EQ(rep.backwards, n / 2);
      return format("%zu backwards dropped (replay report)", rep.backwards);
    default: return std::nullopt;
  }
}

/// The recovery check of a faulted run, one estimate at a time in time order: the worst error
/// from the fault's begin until `recovery_s` after it is over (`during`), and in the check
/// window (the `window_s` after that) every error within its bound, the worst error and the
/// worst share of the bound.
struct Recovery {
  const Fault& f;
  double recovery_s, window_s;
  double t0 = 0.0;  // the clock's origin, for the failure messages
  double during = 0.0, worst = 0.0, share = 0.0;
  std::size_t checked = 0;

  /// Takes the error `err` of an estimate at original time `t`; whether `t` is in the check
  /// window (then the caller checks it against its bound).
  bool take(double t, double err) {
    if (t >= f.begin && t < f.over() + recovery_s) during = std::max(during, err);
    return t >= f.over() + recovery_s && t <= f.over() + recovery_s + window_s;
  }
  void check(double t, double err, double bound) {
    EXPECT_LE(err, bound) << "t " << t - t0;
    ++checked;
    worst = std::max(worst, err);
    share = std::max(share, err / bound);
  }
};

/// The simulated drive of the region and UWB pipelines' fault tests: the default scenario,
/// seed 11, its sensor log, and the middle of its indoor stretch (where their indoor faults start).
struct SimulatedDrive {
  sim::Drive drive;
  messages::SensorLog log;
  double indoor_middle = 0.0;
};

inline const SimulatedDrive& simulated_drive() {
  static const SimulatedDrive d = [] {
    SimulatedDrive k;
    sim::DriveConfig c = sim::scenario_config("default");
    c.seed = 11;
    k.drive = sim::simulate_drive(c);
    k.log = sim::sensor_log(k.drive);
    double first = -1.0, last = -1.0;
    for (const auto& x : k.drive.truth)
      if (x.region == sim::Region::indoor) {
        if (first < 0.0) first = x.t;
        last = x.t;
      }
    k.indoor_middle = 0.5 * (first + last);
    return k;
  }();
  return d;
}

}  // namespace ctxfuse::reliability

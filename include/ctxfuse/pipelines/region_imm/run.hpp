// Runs one estimator of the region pipeline over a recorded or simulated log
// (messages::SensorLog): the time-ordered replay (io/replay.hpp) drives the estimator, which starts
// from the log's own fixes (alignment.hpp) and records its estimate at every receiver epoch.
// Truth never enters: scoring is eval/'s (eval/region_errors.hpp).
//
// Streams and their order at one time stamp: the IMU propagates to each measurement's time;
// then speed samples (the vehicle constraint), UWB ranges, the GNSS fix, and last the
// receiver's epoch (messages::SatEpoch), which ends an IMM cycle.
#pragma once

#include <optional>
#include <span>
#include <stdexcept>
#include <vector>

#include "ctxfuse/io/replay.hpp"
#include "ctxfuse/pipelines/region_imm/alignment.hpp"
#include "ctxfuse/pipelines/region_imm/baselines.hpp"
#include "ctxfuse/pipelines/region_imm/estimators.hpp"

namespace ctxfuse::pipelines::region_imm {

struct RunOptions {
  /// Recognised regions per receiver epoch: needed by the region IMMs only (the posteriors by
  /// Estimator::region_imm_posterior only).
  const RegionTrack* regions = nullptr;
  /// Start at the first fix with this motion instead of aligning dynamically.
  std::optional<KnownMotion> known_motion;
};

/// The estimator's track and what the replay dropped.
struct RunResult {
  Track track;
  io::ReplayReport<4> replay;  // streams: speed, uwb, gnss, sat_epochs
  std::optional<Alignment> alignment;  // how it started (empty with known motion)
};

namespace detail {

/// The replay's handler: aligns, then starts the estimator and forwards every message.
template <class Est>
struct Runner {
  Est& est;
  const Settings& s;
  const std::optional<KnownMotion>& known;
  models::DynamicAligner gnss_aligner{s.alignment_options()};
  models::DynamicAligner uwb_aligner{s.alignment_options()};
  std::vector<messages::UwbRange> stamp{};  // before the start: the ranges of the latest stamp
  bool started = false;
  std::optional<Alignment> alignment{};

  void begin(double t0, const Gaussian<L::size>& b0) {
    est.start(t0, b0);
    started = true;
    stamp.clear();
  }
  void begin(const Alignment& a) {
    alignment = a;
    begin(a.t, models::planar_initial_belief(a, s));
  }
  // A UWB stamp is complete once the replay moves past its time; its snapshot may start the
  // estimator there.
  void flush_stamp() {
    const auto snap = multilaterate(stamp, snapshot_options(s));
    const double t = stamp.front().t;
    stamp.clear();
    if (!snap.ok()) return;
    if (const auto a = uwb_aligner.add(t, snap.position, snap.cov)) begin(*a);
  }

  void propagate(const messages::ImuSample& u, double dt) {
    if (!started && !stamp.empty()) flush_stamp();
    if (started) est.predict(models::planar_input(u), dt);
  }
  void on(const messages::SpeedSample& v) {
    if (started) est.speed(v);
  }
  void on(const messages::UwbRange& r) {
    if (started) {
      est.uwb(r);
      return;
    }
    // A new stamp completes the previous one (when no IMU sample came between them).
    if (!stamp.empty() && stamp.front().t != r.t) flush_stamp();
    if (started)
      est.uwb(r);
    else
      add_to_stamp(stamp, r);
  }
  void on(const messages::GnssFix& fix) {
    if (started) {
      est.gnss(fix);
      return;
    }
    if (known) {
      begin(fix.t, models::planar_initial_belief(Eigen::Vector2d(fix.position.head<2>()), *known, s));
    } else if (const auto a = gnss_aligner.add(fix.t, fix.position.head<2>(), fix.cov.topLeftCorner<2, 2>())) {
      begin(*a);
    }
    // The fix that starts the estimator is in its initial belief, not an update; GNSS alone
    // takes it as its first fix.
    if (started) {
      if constexpr (requires { est.start_fix(fix); }) est.start_fix(fix);
    }
  }
  void on(const messages::SatEpoch& e) {
    if (started) est.epoch(e.t);
  }
};

template <class Est>
RunResult replay_log(const messages::SensorLog& log, Est& est, const Settings& s, const RunOptions& o) {
  if (log.imu.empty()) throw std::invalid_argument("region_imm: the log has no IMU samples");
  if (log.sat_epochs.empty()) throw std::invalid_argument("region_imm: the log has no receiver epochs");
  Runner<Est> runner{est, s, o.known_motion};
  RunResult out;
  out.replay = io::replay(runner, std::span<const messages::ImuSample>(log.imu), std::span<const messages::SpeedSample>(log.speed),
                          std::span<const messages::UwbRange>(log.uwb), std::span<const messages::GnssFix>(log.gnss),
                          std::span<const messages::SatEpoch>(log.sat_epochs));
  if (!runner.started)
    throw std::invalid_argument("region_imm: the log never gave two fixes far enough apart to start from");
  out.alignment = runner.alignment;
  if constexpr (requires { est.track(); })
    out.track = est.track();
  else
    out.track = est.track;
  return out;
}

template <class Mixing>
Mixing make_mixing(const Settings& s);
template <>
inline policies::FixedTransition<3> make_mixing(const Settings& s) {
  return policies::FixedTransition<3>(policies::sticky_transition<3>(s.stay_probability));
}
template <>
inline policies::RegionAdaptiveTransition<3> make_mixing(const Settings& s) {
  return policies::RegionAdaptiveTransition<3>(policies::sticky_transition<3>(s.stay_probability), s.prior_weight,
                                                1.0 - s.prior_weight);
}
template <>
inline policies::PosteriorPull<3, policies::RegionAdaptiveTransition<3>> make_mixing(const Settings& s) {
  return policies::PosteriorPull<3, policies::RegionAdaptiveTransition<3>>(
      make_mixing<policies::RegionAdaptiveTransition<3>>(s), s.posterior_pull);
}

}  // namespace detail

namespace detail {
/// run()'s body. A template only so that the compiled target ctxfuse::instances can hold its one
/// instance (instances/region_imm.hpp declares it extern): every estimator below is instantiated
/// here, the cost of a source that calls run().
template <class = void>
RunResult run_any(const messages::SensorLog& log, Estimator e, const Settings& s, const RunOptions& o,
                  UpdateObserver observer) {
  auto aided = [&](auto core) {
    Aided<decltype(core)> est(std::move(core), s, observer);
    return replay_log(log, est, s, o);
  };
  switch (e) {
    case Estimator::gnss: {
      GnssOnly est;
      return replay_log(log, est, s, o);
    }
    case Estimator::uwb: {
      UwbOnly est{.s = s};
      return replay_log(log, est, s, o);
    }
    case Estimator::odr:
    case Estimator::iotr:
    case Estimator::idr: {
      const int k = e == Estimator::odr ? 0 : e == Estimator::iotr ? 1 : 2;
      return aided(SingleCore{&s, k != 2, k != 0, s.mode_process_noise_factor[static_cast<std::size_t>(k)],
                              k == 1 ? s.iotr_noise_factor : 1.0});
    }
    case Estimator::fkf: return aided(FederatedCore{&s});
    case Estimator::fkf_static: return aided(FederatedCore{&s, true});
    case Estimator::imm: {
      using M = policies::FixedTransition<3>;
      return aided(ImmCore<M>{&s, make_mixing<M>(s), nullptr});
    }
    case Estimator::region_imm: {
      if (!o.regions) throw std::invalid_argument("region_imm: the region-aware IMM needs the recognised regions");
      using M = policies::RegionAdaptiveTransition<3>;
      return aided(ImmCore<M>{&s, make_mixing<M>(s), o.regions});
    }
    case Estimator::region_imm_posterior: {
      if (!o.regions || o.regions->posterior.size() != o.regions->t.size())
        throw std::invalid_argument("region_imm: the posterior-pull IMM needs the recognised regions and their posteriors");
      using M = policies::PosteriorPull<3, policies::RegionAdaptiveTransition<3>>;
      return aided(ImmCore<M>{&s, make_mixing<M>(s), o.regions});
    }
  }
  throw std::invalid_argument("region_imm: unknown estimator");
}
}  // namespace detail

/// Runs one estimator over the log; `observer` (a pointer to anything callable with a const
/// UpdateEvent&) sees every GNSS and UWB update of the IMU-driven estimators (aided.hpp).
/// Throws std::invalid_argument when the log cannot drive the pipeline (no IMU, no epochs,
/// never aligned) or a region IMM lacks its regions. (A template, called as a function, so that
/// a source that includes this header without calling it compiles none of the estimators.)
template <class = void>
RunResult run(const messages::SensorLog& log, Estimator e, const Settings& s, const RunOptions& o = {},
              UpdateObserver observer = {}) {
  return detail::run_any(log, e, s, o, observer);
}

}  // namespace ctxfuse::pipelines::region_imm

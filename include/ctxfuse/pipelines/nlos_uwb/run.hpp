// The run loop of the NLOS-robust UWB pipeline on io::replay (without an IMU stream the estimator's
// motion model predicts from the range times; with one, `run(imu, ranges, ...)` hands each
// piece of it to the estimator's add_imu, imu_smoother.hpp). Ranges are grouped into epochs (one range per
// anchor within settings.epoch_window_s of the epoch's first); for each epoch:
//   1. the estimator predicts to the epoch's first range; its speed is the classifiers' v_i;
//   2. every range gets a verdict (classifier.hpp), attached or not, so the per-anchor range
//      differences stay consecutive;
//   3. the policy (policies.hpp) picks the ranges that enter, and the estimator takes the epoch
//      with that mask (estimators.hpp: the EKF applies each range at its own time, the
//      smoother adds one state at the epoch's last range);
//   4. one estimate per epoch, at its last range's time.
// Before the estimator has a belief, an epoch with at least three ranges starts it from the
// least-squares fix (filters/multilateration.hpp) that fits best among several starting points
// (the anchors span under 2 m, so the cost has a mirror-image minimum far from them); a failed
// prediction (a gap beyond the filter's maximum dt, a numerical failure) stops it and the next
// fix starts it again. An anchor whose attached ranges the estimator has gated for longer than
// settings.lockout (policies/health.hpp) says the belief has left the truth (e.g. the mirror
// image, which only one anchor can tell apart): the estimator restarts from the epoch's best fix
// when that fix fits its ranges within 3 sigma.
// `least_squares_track` is the LS baseline: one snapshot fix per epoch.
#pragma once

#include <Eigen/Core>

#include <array>
#include <limits>
#include <span>
#include <vector>

#include "ctxfuse/core/status.hpp"
#include "ctxfuse/filters/multilateration.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/io/replay.hpp"
#include "ctxfuse/policies/health.hpp"
#include "ctxfuse/pipelines/nlos_uwb/classifier.hpp"
#include "ctxfuse/pipelines/nlos_uwb/estimators.hpp"
#include "ctxfuse/pipelines/nlos_uwb/policies.hpp"
#include "ctxfuse/pipelines/nlos_uwb/settings.hpp"

namespace ctxfuse::pipelines::nlos_uwb {

inline constexpr int kMaxEpochRanges = NlosClassifier::kMaxAnchors;

struct Estimate {
  double t = 0.0;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  bool epoch_attached = false;  // at least one of the epoch's ranges was attached
};

/// Everything the run said about one range (the identification metrics score these).
struct RangeRecord {
  messages::UwbRange range;
  SvmInput input;
  RangeVerdict verdict;
  bool attached = false;
  Status status = Status::invalid(Problem::time_not_set);  // the estimator's update (if attached)
};

struct Track {
  std::vector<Estimate> estimates;
  std::vector<RangeRecord> ranges;
  std::size_t epochs = 0, epochs_attached = 0, epochs_left_out = 0, starts = 0, restarts = 0;
  std::size_t ranges_attached = 0, ranges_accepted = 0, ranges_gated = 0, ranges_invalid = 0;
};

inline MultilaterationOptions snapshot_options(const Settings& s) {
  MultilaterationOptions o;
  o.tag_height_m = s.tag_height_m;
  o.sigma_m = s.range_sigma_m;
  o.max_rms_m = 3.0 * s.range_sigma_m;  // a start from a fix that fits its ranges within 3 sigma
  return o;
}

/// The snapshot fix with the smallest RMS residual among Gauss-Newton runs from the anchors'
/// centroid and from rings of 8 points at 3, 10, 30 and 60 m around it (the site's scale);
/// not ok when no run gives an accepted fix. `max_rms_m` is the residual test (3 sigma for a
/// start; infinite for the LS baseline, which keeps every solution).
template <class = void>
Multilateration best_snapshot_fix(std::span<const messages::UwbRange> epoch, const Settings& s, double max_rms_m) {
  MultilaterationOptions o = snapshot_options(s);
  o.max_rms_m = max_rms_m;
  Multilateration best = multilaterate(epoch, o);
  if (epoch.size() < 3) return best;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const auto& r : epoch) centre += r.anchor_position.head<2>();
  centre /= static_cast<double>(epoch.size());
  if (!centre.allFinite()) return best;
  for (double radius : {3.0, 10.0, 30.0, 60.0})
    for (int k = 0; k < 8; ++k) {
      const double a = 0.25 * 3.14159265358979323846 * k;
      o.initial = centre + radius * Eigen::Vector2d(std::cos(a), std::sin(a));
      const auto fix = multilaterate(epoch, o);
      if (fix.ok() && (!best.ok() || fix.rms_m < best.rms_m)) best = fix;
    }
  return best;
}

/// Groups ranges into epochs and hands each complete epoch to `process`.
template <class Process>
class EpochAssembler {
 public:
  EpochAssembler(double window_s, Process& process) : window_(window_s), process_(process) {}

  void on(const messages::UwbRange& r) {
    bool repeat = false;
    for (int i = 0; i < n_; ++i) repeat = repeat || epoch_[static_cast<std::size_t>(i)].anchor_id == r.anchor_id;
    if (n_ > 0 && (repeat || n_ == kMaxEpochRanges || r.t - epoch_[0].t > window_)) flush();
    epoch_[static_cast<std::size_t>(n_++)] = r;
  }
  void flush() {
    if (n_ > 0) process_(std::span<const messages::UwbRange>(epoch_.data(), static_cast<std::size_t>(n_)));
    n_ = 0;
  }

 private:
  double window_;
  Process& process_;
  std::array<messages::UwbRange, kMaxEpochRanges> epoch_{};
  int n_ = 0;
};

template <class Estimator, NlosPolicy Policy>
class EpochProcessor {
 public:
  EpochProcessor(const Settings& s, Estimator& est, const Policy& policy, NlosClassifier& classifier, Track& track)
      : settings_(s), est_(est), policy_(policy), classifier_(classifier), track_(track) {}

  void operator()(std::span<const messages::UwbRange> epoch) {
    ++track_.epochs;
    bool started_here = false;
    if (!est_.started()) {
      const auto fix = best_snapshot_fix(epoch, settings_, 3.0 * settings_.range_sigma_m);
      started_here = fix.ok() && est_.start(epoch.front().t, fix.position, fix.cov).accepted();
      track_.starts += started_here ? 1 : 0;
    }
    double speed = 0.0;
    if (est_.started()) {
      if (!est_.predict_to(epoch.front().t).accepted()) est_.stop();
      else speed = est_.velocity().norm();
    }
    std::array<RangeVerdict, kMaxEpochRanges> verdicts{};
    std::array<bool, kMaxEpochRanges> attach{};
    const std::size_t first = track_.ranges.size();
    for (std::size_t i = 0; i < epoch.size(); ++i) {
      RangeRecord rec;
      rec.range = epoch[i];
      verdicts[i] = rec.verdict = classifier_.classify(epoch[i], est_.started() ? speed : 0.0, &rec.input);
      track_.ranges.push_back(rec);
    }
    if (!est_.started()) return;
    if constexpr (!kUsesRanges<Estimator>) {
      if (est_.predict_to(epoch.back().t).accepted()) track_.estimates.push_back({est_.time(), est_.position(), false});
      ++track_.epochs_left_out;
      return;
    }
    if (started_here) {
      // The start's fix was computed from this epoch's ranges: they are in the prior already,
      // and updating with them again would count their information twice. The epoch is
      // attached through the fix; its ranges are not factor updates (no range counts).
      if (!est_.predict_to(epoch.back().t).accepted()) {
        est_.stop();
        return;
      }
      emit(true);
      return;
    }
    policy_.select(std::span<const RangeVerdict>(verdicts.data(), epoch.size()), std::span<bool>(attach.data(), epoch.size()));
    std::array<Status, kMaxEpochRanges> statuses{};
    const Status step = est_.apply_epoch(epoch, std::span<const bool>(attach.data(), epoch.size()),
                                         std::span<Status>(statuses.data(), epoch.size()));
    bool any = false;
    for (std::size_t i = 0; i < epoch.size(); ++i) {
      RangeRecord& rec = track_.ranges[first + i];
      rec.attached = attach[i];
      if (!attach[i]) continue;
      any = true;
      ++track_.ranges_attached;
      rec.status = statuses[i];
      track_.ranges_accepted += rec.status.accepted();
      track_.ranges_gated += rec.status.outcome == Outcome::gated;
      track_.ranges_invalid += rec.status.outcome == Outcome::invalid_input || rec.status.outcome == Outcome::numerical_failure;
      if (SourceHealth* h = health_of(epoch[i].anchor_id)) h->record(epoch[i].t, rec.status);
    }
    if (!step.accepted()) {
      est_.stop();
      return;
    }
    if (locked_out(epoch.back().t)) {
      const auto fix = best_snapshot_fix(epoch, settings_, 3.0 * settings_.range_sigma_m);
      if (fix.ok() && est_.start(epoch.back().t, fix.position, fix.cov).accepted()) {
        ++track_.restarts;
        for (int k = 0; k < health_used_; ++k) health_[static_cast<std::size_t>(k)].recovered();
      }
    }
    if (!est_.predict_to(epoch.back().t).accepted()) {
      est_.stop();
      return;
    }
    emit(any);
  }

 private:
  /// The epoch's estimate, counted as attached (a range or the start fix used) or left out.
  /// A fixed-lag estimator's output is emitted once per state: not again while its window is
  /// shorter than the lag (after a start) or has not moved on. Its `attached` flag is the
  /// newest epoch's, not the lagged state's.
  void emit(bool attached) {
    (attached ? track_.epochs_attached : track_.epochs_left_out) += 1;
    if constexpr (requires(const Estimator& e) { e.output_time(); e.output_position(); }) {
      const double t = est_.output_time();
      if (track_.estimates.empty() || t > track_.estimates.back().t)
        track_.estimates.push_back({t, est_.output_position(), attached});  // a fixed-lag estimate
    } else {
      track_.estimates.push_back({est_.time(), est_.position(), attached});
    }
  }

  using SourceHealth = policies::SourceHealth;
  SourceHealth* health_of(int anchor) {
    for (int k = 0; k < health_used_; ++k)
      if (health_ids_[static_cast<std::size_t>(k)] == anchor) return &health_[static_cast<std::size_t>(k)];
    if (health_used_ == kMaxEpochRanges) return nullptr;
    const auto k = static_cast<std::size_t>(health_used_++);
    health_ids_[k] = anchor;
    health_[k] = SourceHealth(settings_.lockout);
    return &health_[k];
  }
  bool locked_out(double t) const {
    for (int k = 0; k < health_used_; ++k)
      if (health_[static_cast<std::size_t>(k)].lockout(t)) return true;
    return false;
  }

  std::array<int, kMaxEpochRanges> health_ids_{};
  std::array<SourceHealth, kMaxEpochRanges> health_{};
  int health_used_ = 0;
  const Settings& settings_;
  Estimator& est_;
  const Policy& policy_;
  NlosClassifier& classifier_;
  Track& track_;
};

/// The replay handler: no IMU, so only measurements arrive.
template <class Assembler>
struct RangeHandler {
  Assembler& assembler;
  void propagate(const messages::ImuSample&, double) {}
  void on(const messages::UwbRange& r) { assembler.on(r); }
};

/// Runs `estimator` under `policy` over a time-ordered range stream.
template <class Estimator, NlosPolicy Policy>
Track run(std::span<const messages::UwbRange> ranges, Estimator estimator, const Policy& policy, NlosClassifier classifier,
          const Settings& s) {
  Track track;
  track.ranges.reserve(ranges.size());
  EpochProcessor<Estimator, Policy> process(s, estimator, policy, classifier, track);
  EpochAssembler<EpochProcessor<Estimator, Policy>> epochs(s.epoch_window_s, process);
  RangeHandler<decltype(epochs)> handler{epochs};
  io::replay(handler, std::span<const messages::ImuSample>(), ranges);
  epochs.flush();
  return track;
}

/// The replay handler with an IMU stream: the estimator takes each piece of it (add_imu) with
/// the time it starts, which the handler keeps from the samples' stamps and the spans.
template <class Assembler, class Estimator>
struct ImuRangeHandler {
  Assembler& assembler;
  Estimator& estimator;
  double now = std::numeric_limits<double>::quiet_NaN();
  void on(const messages::ImuSample& u) { now = u.t; }  // replay: after the propagation to its stamp
  void propagate(const messages::ImuSample& u, double dt) {
    estimator.add_imu(now, dt, u);
    now += dt;
  }
  void on(const messages::UwbRange& r) { assembler.on(r); }
};

/// Runs an estimator that takes an IMU stream (add_imu) over the IMU and range streams.
template <class Estimator, NlosPolicy Policy>
  requires requires(Estimator& e, const messages::ImuSample& u) { e.add_imu(0.0, 0.0, u); }
Track run(std::span<const messages::ImuSample> imu, std::span<const messages::UwbRange> ranges, Estimator estimator, const Policy& policy,
          NlosClassifier classifier, const Settings& s) {
  Track track;
  track.ranges.reserve(ranges.size());
  EpochProcessor<Estimator, Policy> process(s, estimator, policy, classifier, track);
  EpochAssembler<EpochProcessor<Estimator, Policy>> epochs(s.epoch_window_s, process);
  ImuRangeHandler<decltype(epochs), Estimator> handler{epochs, estimator};
  io::replay(handler, imu, ranges);
  epochs.flush();
  return track;
}

/// Baseline: least-squares multilateration of every epoch on its own, Gauss-Newton from the
/// anchors' centroid without a residual test (every solution kept; degenerate geometry or no
/// convergence gives no estimate). The multi-start's smallest residual is no better here: an
/// NLOS or gross range often fits the mirror image best (8.9 m on LOS case 1 against 0.87 m).
template <class = void>
Track least_squares_track(std::span<const messages::UwbRange> ranges, const Settings& s) {
  Track track;
  MultilaterationOptions o = snapshot_options(s);
  o.max_rms_m = std::numeric_limits<double>::infinity();
  auto process = [&](std::span<const messages::UwbRange> epoch) {
    ++track.epochs;
    const auto fix = multilaterate(epoch, o);
    if (!fix.ok()) return;
    ++track.epochs_attached;
    track.estimates.push_back({epoch.back().t, fix.position, true});
  };
  EpochAssembler<decltype(process)> epochs(s.epoch_window_s, process);
  RangeHandler<decltype(epochs)> handler{epochs};
  io::replay(handler, std::span<const messages::ImuSample>(), ranges);
  epochs.flush();
  return track;
}

}  // namespace ctxfuse::pipelines::nlos_uwb

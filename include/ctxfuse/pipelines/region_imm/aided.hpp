// The aided-filter wrapper: what every IMU-driven estimator of the region pipeline does around
// its filter, in one place (PX4 EKF2's habit of keeping each aiding source's gate and health
// together): the per-source gate health of each taker, the UWB integrity check with its
// re-anchoring, the lock-out recovery at each epoch, the track it records, and the update
// observer. The estimators differ only in their Core (estimators.hpp): one EKF, the federated
// filter, or the IMM.
//
// A Core provides, for its kTakers takers (filters that take measurements and keep their own
// health; kWhole adds the health of the estimator as a whole, the IMM's):
//   start(t0, b0), predict(u, dt) -> Status, speed(v) -> bool (some taker accepted it, or
//   there was nothing to apply), reanchor(fault),
//   integrity_view() -> the belief the integrity check compares with,
//   takes_gnss(), takes_uwb(), watches_uwb() (whether a range feeds the integrity check),
//   gnss(fix), uwb(range) -> Takes (per taker: the update's status, or nothing if not offered),
//   close_cycle(t), position(), dominant_mode(), taker_position(j), widen(j, reach),
//   open_cycle(t).
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "ctxfuse/core/status.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/models/held_input.hpp"
#include "ctxfuse/pipelines/region_imm/models.hpp"
#include "ctxfuse/pipelines/region_imm/settings.hpp"

namespace ctxfuse::pipelines::region_imm {

/// Estimates at the receiver's epochs (ENU x, y).
struct Track {
  std::vector<double> t;
  std::vector<Eigen::Vector2d> estimate;
  std::vector<int> dominant_mode;  // IMMs only (-1 otherwise)
  // Whether the estimator had a solution of its own at the epoch. Filters always do; GNSS
  // alone only with a fix and UWB alone only while its tracker is locked; at the other epochs
  // the position they held is recorded.
  std::vector<bool> solution;
  // Times the UWB integrity check re-anchored the filter (Settings::uwb_integrity; IMU-driven
  // filters that take UWB only).
  int integrity_faults = 0;
  // IMU propagations whose sample the filter refused (non-finite or absurd rates): each was
  // propagated with the last accepted sample instead (models/held_input.hpp says why).
  std::size_t rejected_imu = 0;
  // Speed samples whose vehicle constraint no taker accepted: a non-finite speed under the
  // speed update (refused), or a constraint every taker gated.
  std::size_t rejected_speed = 0;

  void record(double t_epoch, const Eigen::Vector2d& p, int mode = -1, bool has_solution = true) {
    t.push_back(t_epoch);
    estimate.push_back(p);
    dominant_mode.push_back(mode);
    solution.push_back(has_solution);
  }
};

enum class Source : std::uint8_t { gnss, uwb };
inline constexpr int kMaxTakers = 4;

/// One GNSS or UWB update as the estimator's takers saw it: what an update observer receives
/// (the zone and gate study of `ctxfuse region-study` is one). Taker k < takers; for the IMMs
/// the takers are the modes ODR, I-OTR, IDR and the IMM as a whole, which gates an update
/// when no mode that took it accepted it.
struct UpdateEvent {
  Source source = Source::gnss;
  double t = 0.0;
  int anchor_id = -1;  // UWB only
  int takers = 1;
  std::array<bool, kMaxTakers> offered{};
  std::array<bool, kMaxTakers> gated{};
};

/// A non-owning reference to what watches the updates (anything callable with a const
/// UpdateEvent&, given by pointer), or to nothing. A run-time value, not a template parameter:
/// the estimators are compiled once whatever watches them (instances/region_imm.hpp), for one
/// indirect call per update when something does.
class UpdateObserver {
 public:
  UpdateObserver() = default;
  UpdateObserver(std::nullptr_t) {}  // NOLINT: no observer
  template <class F>
    requires std::invocable<F&, const UpdateEvent&>
  UpdateObserver(F* f)  // NOLINT: implicit, as the pointer it replaces
      : object_(const_cast<void*>(static_cast<const void*>(f))), call_(f ? &call<F> : nullptr) {}

  explicit operator bool() const { return call_ != nullptr; }
  void operator()(const UpdateEvent& e) const {
    if (call_) call_(object_, e);
  }

 private:
  template <class F>
  static void call(void* object, const UpdateEvent& e) {
    (*static_cast<F*>(object))(e);
  }

  void* object_ = nullptr;
  void (*call_)(void*, const UpdateEvent&) = nullptr;
};

template <int N>
using Takes = std::array<std::optional<Status>, static_cast<std::size_t>(N)>;

template <class Core>
class Aided {
 public:
  static constexpr int kTakers = Core::kTakers;

  Aided(Core core, const Settings& s, UpdateObserver observer = {})
      : core_(std::move(core)), s_(s), observer_(observer), integrity_{s} {
    health_.fill(FilterHealth(s));
  }

  void start(double t0, const Gaussian<L::size>& b0) { core_.start(t0, b0); }
  /// The fix the start was aligned on (in the initial belief, not an update).
  void start_fix(const messages::GnssFix& fix) { last_fix_ = fix; }

  void predict(const models::PlanarImu& u, double dt) {
    if (integrity_.pending())
      if (const auto fault = integrity_.flush(core_.integrity_view())) {
        core_.reanchor(*fault);
        for (auto& h : health_) h.recovered();
        if (whole_) whole_->recovered();
      }
    // A refused sample is replaced by the last accepted one, as its dropout would be
    // (models/held_input.hpp says why).
    const auto step = [&](const models::PlanarImu& x) { return core_.predict(x, dt); };
    if (held_input_.apply(u, step) != models::InputUse::taken) ++track_.rejected_imu;
  }

  void speed(const messages::SpeedSample& v) {
    if (!core_.speed(v)) ++track_.rejected_speed;
  }

  void uwb(const messages::UwbRange& r) {
    if (!core_.takes_uwb()) return;
    record_health(Source::uwb, r.t, r.anchor_id, core_.uwb(r));
    if (core_.watches_uwb()) integrity_.add(r);
  }

  void gnss(const messages::GnssFix& fix) {
    last_fix_ = fix;
    if (core_.takes_gnss()) record_health(Source::gnss, fix.t, -1, core_.gnss(fix));
  }

  /// End of a receiver epoch: closes the cycle, records the estimate, recovers from lock-outs,
  /// opens the next cycle.
  void epoch(double t) {
    const messages::GnssFix* fix = last_fix_ && last_fix_->t == t ? &*last_fix_ : nullptr;
    core_.close_cycle(t);
    track_.record(t, core_.position(), core_.dominant_mode());
    // A lock-out of the estimator as a whole widens every taker and restarts their counts.
    const bool whole_lock = whole_ && whole_->lockout(t);
    for (int j = 0; j < kTakers; ++j) {
      auto& h = health_[static_cast<std::size_t>(j)];
      const bool own = h.lockout(t);
      if (!own && !whole_lock) continue;
      if (whole_lock) h.recovered();
      const Eigen::Vector2d p = core_.taker_position(j);
      core_.widen(j, std::max(own ? h.reach(fix, p) : 0.0, whole_lock ? whole_->reach(fix, p) : 0.0));
    }
    core_.open_cycle(t);
  }

  Track track() const {
    Track t = track_;
    t.integrity_faults = integrity_.faults;
    return t;
  }
  const Core& core() const { return core_; }

 private:
  void record_health(Source src, double t, int anchor, const Takes<kTakers>& takes) {
    UpdateEvent ev{src, t, anchor, kTakers + (whole_ ? 1 : 0), {}, {}};
    const Status* any_accepted = nullptr;
    const Status* any_gated = nullptr;
    for (std::size_t j = 0; j < takes.size(); ++j) {
      if (!takes[j]) continue;
      const Status& st = *takes[j];
      (src == Source::gnss ? health_[j].gnss : health_[j].uwb).record(t, st);
      ev.offered[j] = true;
      ev.gated[j] = st.outcome == Outcome::gated;
      if (st.accepted()) any_accepted = &st;
      if (st.outcome == Outcome::gated) any_gated = &st;
    }
    if (whole_) {
      // Accepted by one taker is accepted by the whole; gated by the whole only when no taker
      // accepted it.
      const Status* st = any_accepted ? any_accepted : any_gated;
      if (st) (src == Source::gnss ? whole_->gnss : whole_->uwb).record(t, *st);
      const auto w = static_cast<std::size_t>(kTakers);
      ev.offered[w] = std::any_of(ev.offered.begin(), ev.offered.begin() + kTakers, [](bool b) { return b; });
      ev.gated[w] = !any_accepted && any_gated;
    }
    observer_(ev);
  }

  Core core_;
  const Settings& s_;
  UpdateObserver observer_;
  std::array<FilterHealth, static_cast<std::size_t>(kTakers)> health_{};
  std::optional<FilterHealth> whole_ = Core::kWhole ? std::optional<FilterHealth>(FilterHealth(s_)) : std::nullopt;
  UwbIntegrity integrity_;
  std::optional<messages::GnssFix> last_fix_;
  models::HeldInput<models::PlanarImu> held_input_;
  Track track_;
};

}  // namespace ctxfuse::pipelines::region_imm

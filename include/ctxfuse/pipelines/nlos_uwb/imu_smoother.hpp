// The NLOS-robust UWB smoother with IMU factors (the paper's graph): one window state per
// epoch as in RangeSmoother (smoother.hpp), but the planar IMU state (models/planar.hpp:
// position, velocity, heading, yaw-rate bias, forward/lateral accelerometer bias) and, between
// consecutive states, the IMU factor of the samples in force over the interval instead of a
// constant-velocity motion factor. The samples are preintegrated once, at the previous state's
// biases (models/planar_preintegration.hpp), so a linearisation of the factor costs a few 2 x 2
// products however many samples the interval holds; it equals the re-chained samples
// (models/planar_interval.hpp) at those biases and is corrected to first order in the biases.
//
// The IMU stream reaches the estimator through add_imu (run.hpp's IMU overload of `run`), as
// pieces (sample, start, span) that io::replay cuts at measurement times; an epoch's interval
// is assembled from the pieces between the previous state's time and its own. A refused sample
// (non-finite, absurd rates) is replaced by the last accepted one over its span (HeldInput's
// rule), and a stretch without pieces is covered by the sample before it.
//
// Start: a planar IMU state needs a heading, which one snapshot fix does not give; start()
// offers each fix to a dynamic aligner (models/alignment.hpp: the heading of the
// longest baseline of fixes > align_min_distance_m apart) and the smoother starts at the fix
// that completes it. Until then start() refuses with Problem::time_not_set and the run loop
// offers the next epoch's fix.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <type_traits>
#include <utility>

#include "ctxfuse/core/gaussian.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/filters/fixed_lag.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/models/planar.hpp"
#include "ctxfuse/models/planar_interval.hpp"
#include "ctxfuse/models/planar_preintegration.hpp"
#include "ctxfuse/models/planar_start.hpp"
#include "ctxfuse/pipelines/nlos_uwb/estimators.hpp"
#include "ctxfuse/pipelines/nlos_uwb/smoother.hpp"

namespace ctxfuse::pipelines::nlos_uwb {

/// The IMU's error model (from its data sheet) and the start. The defaults are the data sheet
/// of the simulator's consumer MEMS IMU (sim/config.hpp ImuConfig); a recording with another IMU
/// sets its own sheet's figures. Bias instabilities given as first-order Gauss-Markov
/// processes (sigma, tau) enter as random walks of the same short-term growth,
/// sigma sqrt(2 / tau).
struct ImuFusionSettings {
  double accel_noise_density = 1.0e-3;  // [m/s^2/sqrt(Hz)] white specific-force noise
  double gyro_noise_density = 8.7e-5;   // [rad/s/sqrt(Hz)]
  double accel_bias_sigma = 0.02;       // [m/s^2] turn-on bias, 1 sigma
  double gyro_bias_sigma = 8.7e-5;      // [rad/s]
  double bias_tau_s = 300.0;            // Gauss-Markov correlation time of both biases
  // Alignment (models::DynamicAligner, models/planar_start.hpp): the heading of two
  // snapshot fixes at least align_min_distance_m apart within align_max_span_s, once the
  // fixes' covariances put its 1-sigma below align_max_heading_sigma_deg; the velocity over
  // >= align_velocity_baseline_s.
  // The floors of the aligned belief: the vehicle may turn or change speed between the fixes.
  double align_min_distance_m = 5.0;
  double align_max_span_s = 10.0;
  double align_max_heading_sigma_deg = 5.0;
  double align_velocity_baseline_s = 1.0;
  double init_velocity_sigma_mps = 0.2;
  double init_heading_sigma_deg = 2.0;

  models::PlanarImuModel model() const {
    models::PlanarImuModel m;
    m.accel_noise_density = accel_noise_density;
    m.gyro_noise_density = gyro_noise_density;
    m.accel_bias_walk = accel_bias_sigma * std::sqrt(2.0 / bias_tau_s);
    m.gyro_bias_walk = gyro_bias_sigma * std::sqrt(2.0 / bias_tau_s);
    return m;
  }
  /// The start's settings (models/planar_start.hpp): the aligner's and the initial belief's.
  models::PlanarStartSettings start(const Settings& s) const {
    models::PlanarStartSettings a;
    a.align_min_distance_m = align_min_distance_m;
    a.align_max_span_s = align_max_span_s;
    a.align_max_heading_sigma_deg = align_max_heading_sigma_deg;
    a.align_velocity_baseline_s = align_velocity_baseline_s;
    a.init_position_sigma = s.range_sigma_m;  // floor only: the fix's own covariance is used
    a.init_velocity_sigma = init_velocity_sigma_mps;
    a.init_heading_sigma_deg = init_heading_sigma_deg;
    a.init_gyro_bias_sigma = gyro_bias_sigma;
    a.init_accel_bias_sigma = accel_bias_sigma;
    return a;
  }
};

/// The range model of `r` on the planar IMU state (tag height and ranging sigma from settings).
inline models::PlanarRange planar_range(const messages::UwbRange& r, const Settings& s) {
  models::PlanarRange h;
  h.anchor = r.anchor_position;
  h.tag_height = s.tag_height_m;
  h.sigma = s.range_sigma_m;
  return h;
}

/// The IMU pieces not yet consumed by a state, oldest first, in a ring of fixed capacity (the
/// oldest are dropped when it is full: only pieces after the newest state are ever needed).
class ImuPieces {
 public:
  static constexpr int kCapacity = 128;  // 1.28 s at 100 Hz; an epoch needs ~0.15 s of them

  /// Appends one piece (sample u in force over [t, t + span)); a refused sample is replaced by
  /// the last accepted one, and dropped when there is none.
  void add(double t, double span, const models::PlanarImu& u, const models::PlanarImuModel& m) {
    if (!std::isfinite(t) || !(span > 0.0) || !std::isfinite(span)) return;
    const bool ok = u.is_finite() && m.check_input(u) == Problem::none;
    if (ok) {
      last_ = u;
      has_last_ = true;
    } else if (!has_last_) {
      return;
    }
    if (count_ == kCapacity) drop_oldest();
    ring_[index(count_++)] = Piece{t, span, ok ? u : last_};
  }

  /// The samples in force over [t0, t1] (a stretch without pieces is covered by the sample
  /// before it, or after it at the start), handed in time order to out.add(sample, span): a
  /// models::PlanarImuInterval (cleared first) or a models::PlanarPreintegrated (reset by the
  /// caller at its biases). False when no piece reaches the interval or `out` refuses one.
  template <class Sink>
  bool interval(double t0, double t1, Sink& out) const {
    if constexpr (requires { out.clear(); }) out.clear();
    bool ok = true;
    int added = 0;
    auto put = [&](const models::PlanarImu& u, double span) {
      ++added;
      if constexpr (std::is_void_v<decltype(out.add(u, span))>)
        out.add(u, span);
      else
        ok = ok && out.add(u, span) == Problem::none;
    };
    constexpr double kMinSpan = 1e-9;  // replay's accumulated clock meets range stamps to ~1e-15 s
    double cursor = t0;
    const models::PlanarImu* held = nullptr;
    for (int k = 0; k < count_ && cursor < t1 - kMinSpan; ++k) {
      const Piece& p = ring_[index(k)];
      const double end = p.t + p.span;
      if (end <= cursor + kMinSpan) {
        held = &p.u;
        continue;
      }
      if (p.t >= t1) break;
      if (p.t > cursor + kMinSpan) put(held ? *held : p.u, p.t - cursor);
      cursor = std::max(cursor, p.t);
      const double stop = std::min(end, t1);
      if (stop > cursor) put(p.u, stop - cursor);
      cursor = stop;
      held = &p.u;
    }
    if (!held) return false;
    if (cursor < t1 - kMinSpan) put(*held, t1 - cursor);
    return ok && added > 0;
  }

  /// Forgets the pieces that end at or before t (kept: the one in force at t).
  void drop_before(double t) {
    while (count_ > 1 && ring_[index(0)].t + ring_[index(0)].span <= t) drop_oldest();
  }
  int size() const { return count_; }

 private:
  struct Piece {
    double t = 0.0, span = 0.0;
    models::PlanarImu u{};
  };
  std::size_t index(int k) const { return static_cast<std::size_t>((first_ + k) % kCapacity); }
  void drop_oldest() {
    first_ = (first_ + 1) % kCapacity;
    --count_;
  }
  std::array<Piece, kCapacity> ring_{};
  int first_ = 0, count_ = 0;
  models::PlanarImu last_{};
  bool has_last_ = false;
};

template <int K = 10, GatePolicy Gate = policies::ChiSquareGate, int OutputLag = 0>
class ImuRangeSmoother {
  static_assert(OutputLag >= 0 && OutputLag < K, "the reported state must be in the window");

 public:
  static constexpr int kSlots = 16;  // NlosClassifier::kMaxAnchors: one slot per anchor
  using L = models::PlanarLayout;
  using Motion = models::PlanarPreintegratedModel;
  using Smoother = FixedLagSmoother<Motion, models::PlanarRange, K, kSlots>;

  ImuRangeSmoother(const Settings& s, const ImuFusionSettings& imu)
      : settings_(s), imu_model_(imu.model()), smoother_(Motion{}), gate_(make_gate<Gate>(s)),
        align_settings_(imu.start(s)), aligner_(align_settings_.alignment_options()) {}

  bool started() const { return started_; }
  double time() const { return smoother_.time(); }
  Eigen::Vector2d position() const { return L::get<"p">(smoother_.newest()); }
  Eigen::Vector2d velocity() const { return L::get<"v">(smoother_.newest()); }
  double heading() const { return smoother_.newest()(L::offset<"psi">()); }
  void stop() {
    started_ = false;
    aligner_.reset();
  }
  double output_time() const { return lagged().time; }
  Eigen::Vector2d output_position() const { return L::get<"p">(lagged().x); }

  /// One piece of the IMU stream: sample `s` in force over [t, t + span).
  void add_imu(double t, double span, const messages::ImuSample& s) {
    pieces_.add(t, span, models::planar_input(s), imu_model_);
  }

  /// Offers the fix to the aligner; starts (accepted) at the fix that completes an alignment,
  /// refuses (time_not_set) before.
  Status start(double t, const Eigen::Vector2d& p, const Eigen::Matrix2d& P) {
    if (!std::isfinite(t)) return Status::invalid(Problem::non_finite_dt);
    if (!p.allFinite() || !P.allFinite()) return Status::invalid(Problem::non_finite_measurement);
    const auto al = aligner_.add(t, p, P);
    if (!al) return Status::invalid(Problem::time_not_set);
    const Status s = smoother_.initialise(al->t, models::planar_initial_belief(*al, align_settings_));
    started_ = s.accepted();
    fresh_ = started_;
    if (started_) pieces_.drop_before(al->t);
    return s;
  }

  /// The smoother adds states only with an epoch: here only the clock is checked.
  Status predict_to(double t) const { return clock_check(started_, time(), t); }

  Status apply_epoch(std::span<const messages::UwbRange> epoch, std::span<const bool> attach, std::span<Status> statuses) {
    if (auto done = smoother_epoch_check(started_, fresh_, time(), kSlots, epoch, statuses)) return *done;
    const double t = epoch.back().t, dt = t - time();
    // Preintegrated once, at the newest state's biases; the factor corrects them to first
    // order as the window's solution moves them (models/planar_preintegration.hpp).
    const Vector<L::size>& newest = smoother_.newest();
    typename Motion::Input u;
    if (u.reset(imu_model_, newest(L::offset<"bg">()), L::get<"ba">(newest)) != Problem::none)
      return Status::failure(Problem::non_finite_state);
    if (!pieces_.interval(time(), t, u)) return Status::invalid(Problem::non_finite_input);
    if (Problem p = smoother_.motion().check(u, dt); p != Problem::none) return Status::invalid(p);
    SquareMatrix<L::size> F;
    const Vector<L::size> x = smoother_.motion().predict(smoother_.newest(), u, dt, &F);
    const SquareMatrix<L::size> P = F * smoother_.newest_covariance() * F.transpose() + smoother_.motion().noise(smoother_.newest(), u, dt);
    auto range = [&](const messages::UwbRange& r) { return planar_range(r, settings_); };
    const Status s = gated_smoother_step(smoother_, settings_, gate_.threshold(1), range, u, x, P, epoch, attach, statuses);
    if (s.accepted()) pieces_.drop_before(t);
    return s;
  }

  const Smoother& smoother() const { return smoother_; }

 private:
  const typename Smoother::Epoch& lagged() const { return lagged_epoch(smoother_, OutputLag); }

  Settings settings_;
  models::PlanarImuModel imu_model_;  // the IMU's data sheet: the pieces' checks and the preintegration
  Smoother smoother_;
  Gate gate_;
  models::PlanarStartSettings align_settings_;  // what the aligner and the initial belief read
  models::DynamicAligner aligner_;
  ImuPieces pieces_;
  bool started_ = false;
  bool fresh_ = false;
};

}  // namespace ctxfuse::pipelines::nlos_uwb

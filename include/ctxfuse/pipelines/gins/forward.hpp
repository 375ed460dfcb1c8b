// The forward pass of the GNSS/INS error-state filter, as a handler of io::replay over the IMU
// stream and the GNSS fixes (and a magnetometer stream when there is one):
//   propagate(u, dt)  mounting rotation on input, eskf::predict with the full strapdown, the
//                     transition composed into the step records (filters/rts.hpp);
//   on(ImuSample)     static detection from the raw rates; every constraint_interval_s the
//                     constraints switched on: ZUPT / ZIHR while static, NHC while moving;
//   on(GnssFix)       decimation and outage windows decide whether the fix is used: GNSS
//                     position (lever arm) and velocity, each with a one-tailed chi-square
//                     gate; a withheld fix still closes an epoch, so the trajectory has a row
//                     at every GNSS stamp.
// Before the filter starts it levels on the static start (roll, pitch, gyro bias from the
// mean of its samples) and waits for a dynamic alignment (models/alignment.hpp: heading from
// the receiver's velocity or a straight baseline of fixes, once its sigma is small enough).
// More than Settings::imu_max_unmeasured_s without a measured IMU sample loses it: it re-aligns
// the same way once the IMU is back (lose, try_align). A GNSS position or velocity the gate
// refuses three times in a row is released (filters/release.hpp).
// An epoch is every time at which a row is wanted or an update happens; its prior and
// posterior are recorded for the RTS smoother.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/filters/release.hpp"
#include "ctxfuse/filters/rts.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/models/alignment.hpp"
#include "ctxfuse/models/held_input.hpp"
#include "ctxfuse/models/ins_augment.hpp"
#include "ctxfuse/models/ins_input.hpp"
#include "ctxfuse/models/ins_motion.hpp"
#include "ctxfuse/models/ins_updates.hpp"
#include "ctxfuse/pipelines/gins/gnss_schedule.hpp"
#include "ctxfuse/pipelines/gins/initial_belief.hpp"
#include "ctxfuse/pipelines/gins/settings.hpp"
#include "ctxfuse/pipelines/gins/static_start.hpp"

namespace ctxfuse::pipelines::gins {

/// The installation's IMU axes turned by yaw, then pitch, then roll (about the turned axes) are
/// the body axes: R = Rz(yaw) Ry(pitch) Rx(roll) holds the body axes in IMU coordinates, so a
/// vector's body coordinates are R' v_imu (the convention of RTKLIB-style rpy installation
/// figures: with the drive's 180 / -6.79 / 185.35 deg the static start's specific force comes
/// out as (0.0, 0.19, -9.97) m/s^2, level within the parking place's 1 deg).
inline Eigen::Matrix3d body_from_imu(const Installation& inst) {
  const Eigen::Vector3d a = inst.imu_rpy_deg * kDeg;
  return models::mounting_rotation(a(0), a(1), a(2)).transpose();
}


struct PassCounts {
  std::size_t imu_steps = 0, imu_refused = 0, filter_failures = 0;
  std::size_t gnss_used = 0, gnss_withheld = 0, gnss_decimated = 0, gnss_gated = 0, gnss_refused = 0, gnss_released = 0;
  std::size_t velocity_used = 0, velocity_gated = 0, velocity_released = 0;
  std::size_t zupt = 0, zupt_gated = 0, zihr = 0, zihr_gated = 0, nhc = 0, nhc_gated = 0, mag = 0, mag_gated = 0;
  std::size_t static_samples = 0;
  std::size_t static_but_moving = 0;  // IMU samples still by the detector, moving by the filter's speed
  std::size_t imu_losses = 0, realignments = 0;  // IMU gaps past imu_max_unmeasured_s, and re-alignments after them
};

template <class Model>
class ForwardPass {
 public:
  using S = typename Model::State;
  using B = eskf::Belief<Model>;

  ForwardPass(const Settings& s, const Installation& inst, const Constraints& c, std::vector<OutageWindow> windows,
              double gnss_rate_hz)
      : s_(s), c_(c), windows_(std::move(windows)), decimator_(gnss_rate_hz),
        detector_(s.static_window_s, s.static_gyro_threshold, s.static_accel_threshold),
        gate_(s.gate_probability),
        align_(alignment_options(s)),
        start_acc_(s.static_window_s),
        gnss_health_(s.gate_release), velocity_health_(s.gate_release),
        speeds_(s.static_max_speed_mps, s.static_gnss_hold_s) {
    thresholds_.gyro = s.static_gyro_threshold;
    thresholds_.accel = s.static_accel_threshold;
    Nav15* nav = nullptr;
    if constexpr (requires { model_.base; }) nav = &model_.base; else nav = &model_;
    nav->gyro_noise_density = s.gyro_noise_density;
    nav->accel_noise_density = s.accel_noise_density;
    nav->gyro_bias = models::GaussMarkov{s.gyro_bias_density};
    nav->accel_bias = models::GaussMarkov{s.accel_bias_density};
    imu_.body_from_imu = body_from_imu(inst);
    gnss_.lever_arm = inst.gnss_lever_m - inst.imu_lever_m;
    gnss_velocity_.lever_arm = gnss_.lever_arm;
    nhc_.vehicle.lever_arm = -inst.imu_lever_m;  // IMU -> system origin
    nhc_.sigma = s.nhc_sigma_mps;
    zupt_.sigma = s.zupt_sigma_mps;
    zihr_.sigma = s.zihr_sigma;
    mag_heading_.sigma = s.mag_heading_sigma;
  }

  void reserve(std::size_t epochs) { rts_.reserve(epochs); used_.reserve(epochs); }
  void set_progress(std::function<void(double)> f, double t_first, double t_last) {
    progress_ = std::move(f);
    t_first_ = t_first;
    t_span_ = t_last > t_first ? t_last - t_first : 1.0;
  }

  void propagate(const messages::ImuSample& u, double dt) {
    models::BodyIncrements inc;
    if (!aligned_) {
      // Lost (below): a new sample the strapdown takes means the IMU is back.
      if (lost_ && u.t != sample_t_) {
        if (imu_.from_rates(u.gyro, u.accel, dt, inc).accepted()) imu_back_ = true;
        else ++counts_.imu_refused;
      }
      return;
    }
    close_epoch();
    // A refused sample (non-finite, absurd) is replaced by the last accepted one over its
    // interval (models/held_input.hpp): time and covariance advance.
    const models::InputUse use =
        held_imu_.apply(u, [&](const messages::ImuSample& s) { return imu_.from_rates(s.gyro, s.accel, dt, inc); });
    if (use != models::InputUse::taken) ++counts_.imu_refused;
    if (use == models::InputUse::lost) return;
    // Time no sample measured: a refused sample's interval, and a sample's beyond imu_hold_s
    // after its stamp (the next did not come); a new sample taken ends the run. Past
    // imu_max_unmeasured_s in a row the strapdown has nothing to go on: the pass is lost and
    // re-aligns (lose, try_align). A slow IMU (10 Hz: half of each interval beyond 50 ms) is
    // never lost: each new sample ends its run.
    if (u.t != sample_t_) {
      sample_t_ = u.t;
      sample_elapsed_ = 0.0;
      if (use == models::InputUse::taken) unmeasured_ = 0.0;
    }
    const double before = sample_elapsed_;
    sample_elapsed_ += dt;
    unmeasured_ += use == models::InputUse::taken
                       ? std::max(0.0, sample_elapsed_ - s_.imu_hold_s) - std::max(0.0, before - s_.imu_hold_s)
                       : dt;
    if (unmeasured_ > s_.imu_max_unmeasured_s) {
      lose();
      return;
    }
    SquareMatrix<Model::dim> F;
    const Status st = eskf::predict(model_, belief_, inc, dt, {}, &F);
    if (!st.accepted()) {
      ++counts_.filter_failures;
      return;
    }
    rts_.predicted(F);
    ++counts_.imu_steps;
  }

  void on(const messages::ImuSample& u) {
    const Eigen::Vector3d w = imu_.body_from_imu * u.gyro, f = imu_.body_from_imu * u.accel;
    if (!w.allFinite() || !f.allFinite()) return;
    gyro_body_ = w;
    Eigen::Vector2d horizontal = Eigen::Vector2d::Zero();
    if (aligned_) {
      const models::NavState x = nav_part<Model>(belief_.nominal);
      horizontal = (x.get<"theta">() * (f - x.get<"ba">())).head<2>();
    }
    const bool still = detector_.push(u.t, w, f, horizontal);
    // Once aligned, a still IMU is static only at a speed near zero (SpeedEvidence).
    bool st = still;
    if (still && aligned_) {
      st = speeds_.allow_static(u.t, nav_part<Model>(belief_.nominal).template get<"v">().template head<2>().norm());
      counts_.static_but_moving += st ? 0 : 1;
    }
    if (st) ++counts_.static_samples;
    // The static start: every static sample before the (first) alignment.
    if (st && !aligned_ && !lost_) {
      start_acc_.add(u.t, w, f);
      start_ = start_acc_.stats();
    }
    if (progress_ && ++since_progress_ >= 2000) {
      since_progress_ = 0;
      progress_((u.t - t_first_) / t_span_);
    }
    if (!aligned_) return;
    if (detector_.entered_static())
      held_heading_ = models::heading_of(nav_part<Model>(belief_.nominal).template get<"theta">().toRotationMatrix());
    if (!st) held_heading_.reset();
    if (!c_.any() || u.t < next_constraint_t_) return;
    next_constraint_t_ = u.t + s_.constraint_interval_s - 1e-6;
    if (st) {
      if (c_.zupt) count(update(u.t, zupt_, Vector<3>(Vector<3>::Zero())), counts_.zupt, counts_.zupt_gated);
      if (c_.zihr && held_heading_) count(update(u.t, zihr_, Vector<1>(*held_heading_)), counts_.zihr, counts_.zihr_gated);
    } else {
      if (c_.nhc) {
        nhc_.vehicle.gyro = w;
        count(update(u.t, nhc_, Vector<2>(Vector<2>::Zero())), counts_.nhc, counts_.nhc_gated);
      }
    }
  }

  void on(const messages::MagSample& m) {
    if (!aligned_ || !c_.mag) return;
    const Eigen::Matrix3d C = nav_part<Model>(belief_.nominal).template get<"theta">().toRotationMatrix();
    const Eigen::Vector3d b = imu_.body_from_imu * m.field_ut;
    if (!mag_.active()) {
      if (detector_.is_static()) mag_.start(C, b);
    } else if (const auto z = mag_.heading(C, b)) {
      count(update(m.t, mag_heading_, Vector<1>(*z)), counts_.mag, counts_.mag_gated);
    }
  }

  void on(const messages::GnssFix& fix) {
    const bool kept = decimator_.keep(fix.t);
    const bool withheld = in_any(windows_, fix.t);
    const bool use = kept && !withheld && fix.frame == messages::PositionFrame::geodetic;
    counts_.gnss_decimated += kept ? 0 : 1;
    counts_.gnss_withheld += kept && withheld ? 1 : 0;
    const Eigen::Vector3d z(fix.position(0) * kDeg, fix.position(1) * kDeg, fix.position(2));
    const Eigen::Matrix3d cov = floored(models::ned_from_enu_cov(fix.cov), s_.gnss_sigma_floor(fix.quality));
    if (!aligned_) {
      if (use && (!lost_ || imu_back_)) try_align(fix, z, cov);
      return;
    }
    open_epoch(fix.t);
    if (!use) return;
    if (!cov.allFinite() || !z.allFinite()) {
      ++counts_.gnss_refused;
      return;
    }
    gnss_.R = models::geodetic_position_noise(z, cov);
    // After Settings::gate_release fixes in a row refused by the gate it is the filter that is
    // off, not the receiver: the next fix is released into the filter (filters/release.hpp; the
    // counts say so). The fix's velocity below, the same.
    const Status st = update_or_release<"p">(fix.t, gnss_, z, gnss_health_, counts_.gnss_released);
    if (st.accepted()) {
      ++counts_.gnss_used;
      pending_used_ = 1;
    } else if (st.outcome == Outcome::gated) {
      ++counts_.gnss_gated;
    } else {
      ++counts_.gnss_refused;
    }
    if (s_.use_gnss_velocity && fix.velocity) {
      const Eigen::Vector3d v(fix.velocity->y(), fix.velocity->x(), -fix.velocity->z());
      gnss_velocity_.R = floored(models::ned_from_enu_cov(fix.velocity_cov), s_.gnss_velocity_sigma_floor_mps);
      speeds_.gnss_velocity(fix.t, v.head<2>());
      gnss_velocity_.gyro = gyro_body_;
      if (gnss_velocity_.R.allFinite())
        count(update_or_release<"v">(fix.t, gnss_velocity_, v, velocity_health_, counts_.velocity_released),
              counts_.velocity_used, counts_.velocity_gated);
    }
  }

  /// Closes the last epoch; call once after the replay.
  void finish() { close_epoch(); }

  bool aligned() const { return aligned_; }
  /// The filter's belief now (meaningful once aligned).
  const B& belief() const { return belief_; }
  double alignment_time() const { return align_t_; }
  /// The alignment the pass started (or last re-started) from.
  const models::PlanarAlignment& alignment() const { return alignment_; }
  const PassCounts& counts() const { return counts_; }
  const StaticStats& static_start() const { return start_; }
  /// The static test's thresholds in force: the fallback, or from the static start once aligned.
  const StaticThresholds& static_thresholds() const { return thresholds_; }
  RtsRecorder<Model>& recorder() { return rts_; }
  const std::vector<char>& gnss_used_per_epoch() const { return used_; }
  const Model& model() const { return model_; }
  const Eigen::Vector3d& gnss_lever() const { return gnss_.lever_arm; }

 private:
  static Eigen::Matrix3d floored(Eigen::Matrix3d cov, double sigma) {
    for (int i = 0; i < 3; ++i) cov(i, i) = std::max(cov(i, i), sigma * sigma);
    return cov;
  }
  void open_epoch(double t) {
    if (open_) return;
    prior_ = belief_;
    open_t_ = t;
    open_ = true;
  }
  void close_epoch() {
    if (!open_) return;
    open_ = false;
    const std::size_t before = rts_.records().size();
    if (rts_.record(open_t_, prior_, belief_).accepted()) {
      if (rts_.records().size() > before) used_.push_back(pending_used_);
      else if (!used_.empty()) used_.back() = static_cast<char>(used_.back() | pending_used_);  // joined the newest epoch
    }
    pending_used_ = 0;
  }
  /// A GNSS position or velocity through the gate, or released once its health declares a
  /// lock-out (filters/release.hpp).
  template <FixedString Name, class Meas>
  Status update_or_release(double t, const Meas& meas, const Vector<3>& z, policies::SourceHealth& health,
                           std::size_t& released) {
    bool was_released = false;
    const Status st = eskf::update_or_release<Name>(model_, meas, belief_, z, gate_, health, t, &was_released);
    released += was_released ? 1 : 0;
    return st;
  }
  template <class Meas, int M>
  Status update(double t, const Meas& meas, const Vector<M>& z) {
    open_epoch(t);
    return eskf::update(model_, meas, belief_, z, gate_);
  }
  void count(const Status& st, std::size_t& used, std::size_t& gated) {
    if (st.accepted()) ++used;
    else if (st.outcome == Outcome::gated) ++gated;
    else ++counts_.filter_failures;
  }

  /// The IMU stopped measuring (a dropout, refused samples, a clock jump) for longer than a
  /// held sample can stand for a car's motion: the pass stops, keeps what the gap does not
  /// change (biases, mounting, lever arm, roll and pitch) and re-aligns from the next good
  /// fixes once the IMU is back, as at the start. The RTS records restart there.
  /// While lost, belief_ is left as it was (nothing predicts or updates it) and is what the
  /// re-alignment keeps from.
  void lose() {
    aligned_ = false;
    lost_ = true;
    imu_back_ = false;
    unmeasured_ = 0.0;
    align_.reset();
    align_empty_ = true;
    held_heading_.reset();
    mag_ = models::MagRelativeHeading{};  // its reference attitude is the lost one
    gnss_health_.recovered();
    velocity_health_.recovered();
    ++counts_.imu_losses;
  }

  /// Offers a used fix to the aligner, in a (north, east) plane about the first fix it holds,
  /// with the receiver's velocity when the fix has one; starts the filter once it aligns.
  void try_align(const messages::GnssFix& fix, const Eigen::Vector3d& z, const Eigen::Matrix3d& cov) {
    if (!cov.allFinite() || !z.allFinite()) return;
    if (align_empty_) {
      align_origin_ = z;
      align_empty_ = false;
    }
    models::PlanarFix pf;
    pf.t = fix.t;
    pf.p = earth::GeodeticRetraction::difference(z, align_origin_).head<2>();
    pf.cov = cov.topLeftCorner<2, 2>();
    if (s_.use_gnss_velocity && fix.velocity) {
      pf.has_velocity = true;
      pf.v = Eigen::Vector2d(fix.velocity->y(), fix.velocity->x());
      pf.v_cov = floored(models::ned_from_enu_cov(fix.velocity_cov), s_.gnss_velocity_sigma_floor_mps).topLeftCorner<2, 2>();
    }
    const auto a = align_.add(pf);
    if (!a) return;
    const B b = initial_belief<Model>(s_, *a, fix, z, cov, gnss_.lever_arm, nhc_.vehicle.lever_arm, start_,
                                      lost_ ? &belief_ : nullptr);
    if (lost_) {
      if (!rts_.restart(fix.t, b).accepted()) return;
      used_.push_back(1);
      ++counts_.realignments;
    } else {
      rts_.start(fix.t, b);
      used_.assign(1, 1);
      // The static start is over: its statistics set the static test's thresholds.
      const auto t = s_.static_thresholds_from_start
                         ? static_thresholds_from_rest(start_, detector_.window_samples(), s_.static_calibration_min_s,
                                                       s_.static_false_alarm, s_.static_gyro_floor_density,
                                                       s_.static_accel_floor_density)
                         : std::nullopt;
      if (t) {
        thresholds_ = *t;
        detector_.calibrate(t->gyro, t->accel, t->gyro_bias);
      }
    }
    belief_ = b;
    alignment_ = *a;
    if (pf.has_velocity) speeds_.gnss_velocity(fix.t, pf.v);
    lost_ = false;
    aligned_ = true;
    align_t_ = fix.t;
    next_constraint_t_ = fix.t;
  }

  const Settings& s_;
  Constraints c_;
  std::vector<OutageWindow> windows_;
  Decimator decimator_;
  models::StaticDetector detector_;
  policies::ChiSquareGate gate_;
  Model model_{};
  models::ImuInput imu_;
  models::HeldInput<messages::ImuSample> held_imu_;
  models::DynamicAligner align_;
  Eigen::Vector3d align_origin_ = Eigen::Vector3d::Zero();  // geodetic origin of the aligner's (north, east) plane
  models::PlanarAlignment alignment_{};
  models::GnssGeodeticPosition<S> gnss_;
  models::GnssVelocity<S> gnss_velocity_;
  models::ZeroVelocity<S> zupt_;
  models::Heading<S> zihr_;
  models::NonHolonomic<S> nhc_;
  models::Heading<S> mag_heading_;
  models::MagRelativeHeading mag_;
  B belief_{}, prior_{};
  RtsRecorder<Model> rts_;
  std::vector<char> used_;
  char pending_used_ = 0;
  bool open_ = false, aligned_ = false;
  double open_t_ = 0.0, align_t_ = NAN, next_constraint_t_ = 0.0;
  std::optional<double> held_heading_;
  Eigen::Vector3d gyro_body_ = Eigen::Vector3d::Zero();
  StaticAccumulator start_acc_;
  StaticStats start_{};
  StaticThresholds thresholds_{};
  PassCounts counts_{};
  std::function<void(double)> progress_;
  double t_first_ = 0.0, t_span_ = 1.0;
  int since_progress_ = 0;
  policies::SourceHealth gnss_health_, velocity_health_;
  // IMU gaps (propagate, lose): the sample in force, how long it has been, the unmeasured time
  // in a row.
  double sample_t_ = NAN, sample_elapsed_ = 0.0, unmeasured_ = 0.0;
  bool lost_ = false, imu_back_ = false;
  bool align_empty_ = true;
  SpeedEvidence speeds_;
};

}  // namespace ctxfuse::pipelines::gins

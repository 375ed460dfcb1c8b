// From IMU samples in the IMU's own axes (messages::ImuSample: rates or increments) to the body-frame
// increments the geodetic INS predicts with (models/ins_nav.hpp): the mounting rotation and the
// logging delay applied on input, dt from the time stamps, and the previous increment kept for
// coning and sculling. A refused sample (non-finite or non-increasing stamp, non-finite or
// absurd values) returns a Status and leaves the adapter as it was.
#pragma once

#include <cmath>
#include <limits>

#include "ctxfuse/core/status.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/models/ins_nav.hpp"

namespace ctxfuse::models {

/// IMU axes -> body axes (forward, right, down) from the installation's roll, pitch, yaw [rad]
/// (the rotation that takes the IMU frame onto the body frame, z-y-x order): v_b = C v_imu.
inline Eigen::Matrix3d mounting_rotation(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

struct ImuInput {
  Eigen::Matrix3d body_from_imu = Eigen::Matrix3d::Identity();
  double delay_s = 0.0;       // added to every IMU stamp (a logger's latency is a negative one)
  double max_gyro = 35.0;     // [rad/s] rates above these are a broken sample, not a vehicle
  double max_accel = 400.0;   // [m/s^2]

  /// The sample with its stamp corrected by the delay (for a replay that merges streams by time).
  messages::ImuSample apply_delay(messages::ImuSample s) const {
    s.t += delay_s;
    return s;
  }

  /// Rates in IMU axes held over dt -> body increments (the replay's propagate(u, dt)).
  Status from_rates(const Eigen::Vector3d& gyro_imu, const Eigen::Vector3d& accel_imu, double dt,
                    BodyIncrements& out) {
    if (!std::isfinite(dt)) return Status::invalid(Problem::non_finite_dt);
    if (dt <= 0.0) return Status::invalid(Problem::non_positive_dt);
    if (Problem p = check_rates(gyro_imu, accel_imu); p != Problem::none) return Status::invalid(p);
    emit(body_from_imu * gyro_imu * dt, body_from_imu * accel_imu * dt, out);
    return Status{};
  }

  /// One sample straight from a recording. A rate sample holds from its stamp to the next one,
  /// so it is used when the next one arrives; an increment sample covers the interval that ends
  /// at its stamp. The first sample only starts the clock (Problem::time_not_set); `dt` is the
  /// step the increments cover.
  Status next(const messages::ImuSample& s, BodyIncrements& out, double& dt) {
    const double t = s.t + delay_s;
    if (!std::isfinite(t)) return Status::invalid(Problem::non_finite_dt);
    if (!all_finite(s.gyro) || !all_finite(s.accel)) return Status::invalid(Problem::non_finite_input);
    if (!std::isfinite(last_t_)) {
      if (!s.increments) {
        if (Problem p = check_rates(s.gyro, s.accel); p != Problem::none) return Status::invalid(p);
      }
      last_t_ = t;
      last_ = s;
      return Status::invalid(Problem::time_not_set);
    }
    const double step = t - last_t_;
    if (step <= 0.0) return Status::invalid(step == 0.0 ? Problem::non_positive_dt : Problem::out_of_order_time);
    if (s.increments) {
      if (Problem p = check_rates(s.gyro / step, s.accel / step); p != Problem::none) return Status::invalid(p);
      emit(body_from_imu * s.gyro, body_from_imu * s.accel, out);
    } else {
      if (Problem p = check_rates(s.gyro, s.accel); p != Problem::none) return Status::invalid(p);
      emit(body_from_imu * last_.gyro * step, body_from_imu * last_.accel * step, out);
    }
    last_t_ = t;
    last_ = s;
    dt = step;
    return Status{};
  }

  /// Starts again (after a gap the previous increment no longer belongs to the next step).
  void restart() {
    last_t_ = std::numeric_limits<double>::quiet_NaN();
    has_previous_ = false;
  }

 private:
  Problem check_rates(const Eigen::Vector3d& w, const Eigen::Vector3d& f) const {
    if (!all_finite(w) || !all_finite(f)) return Problem::non_finite_input;
    if (w.cwiseAbs().maxCoeff() > max_gyro || f.cwiseAbs().maxCoeff() > max_accel) return Problem::input_magnitude;
    return Problem::none;
  }
  void emit(const Eigen::Vector3d& dtheta, const Eigen::Vector3d& dv, BodyIncrements& out) {
    out.dtheta = dtheta;
    out.dv = dv;
    out.prev_dtheta = prev_dtheta_;
    out.prev_dv = prev_dv_;
    out.has_previous = has_previous_;
    prev_dtheta_ = dtheta;
    prev_dv_ = dv;
    has_previous_ = true;
  }

  double last_t_ = std::numeric_limits<double>::quiet_NaN();
  messages::ImuSample last_{};
  Eigen::Vector3d prev_dtheta_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d prev_dv_ = Eigen::Vector3d::Zero();
  bool has_previous_ = false;
};

}  // namespace ctxfuse::models

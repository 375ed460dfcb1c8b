// A level car drive for the gins tests: truth from a speed and yaw-rate profile, integrated with
// the simplified strapdown itself (so the truth obeys the filter's mechanisation exactly and
// only the sensors' errors separate them), the body frame being the vehicle frame (no
// lateral or vertical velocity: the non-holonomic constraint holds exactly). IMU errors from
// the drive's data-sheet figures (../shared/data/README.md, gnss-imu-drive): gyro white noise
// 0.0038 deg/s/sqrt(Hz), accelerometer 70 ug/sqrt(Hz); constant turn-on biases.
#pragma once

#include <functional>
#include <vector>

#include "ctxfuse/models/ins_nav.hpp"
#include "ctxfuse/sim/random.hpp"
#include "states.hpp"

namespace ctxfuse::test {

inline constexpr double kGyroNoise = 0.0038 * kDeg;        // [rad/s/sqrt(Hz)]
inline constexpr double kAccelNoise = 70e-6 * 9.80665;     // [m/s^2/sqrt(Hz)]

struct DriveStep {
  double t = 0.0;                 // end of the step
  models::BodyIncrements imu;     // measured over the step
  Eigen::Vector3d gyro_rate;      // raw rates, for the static detector
  Eigen::Vector3d accel_rate;
  models::NavState truth;         // at t
};

struct Drive {
  models::NavState start;
  std::vector<DriveStep> steps;
  double dt = 0.01;
};

/// speed(t) [m/s] and yaw_rate(t) [rad/s]; biases in rad/s and m/s^2.
inline Drive simulate_drive(double duration, const std::function<double(double)>& speed,
                            const std::function<double(double)>& yaw_rate, const Eigen::Vector3d& gyro_bias,
                            const Eigen::Vector3d& accel_bias, std::uint64_t seed) {
  Drive d;
  const Nav15 m;
  sim::Rng rng(seed, sim::Stream::imu);
  d.start.get<"p">() = Eigen::Vector3d(37.4 * kDeg, -122.1 * kDeg, 30.0);
  d.start.get<"theta">() = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()));
  d.start.get<"v">() = d.start.get<"theta">() * Eigen::Vector3d(speed(0.0), 0.0, 0.0);
  models::NavState x = d.start;
  const int n = static_cast<int>(duration / d.dt + 0.5);
  d.steps.reserve(static_cast<std::size_t>(n));
  const double sg = kGyroNoise * std::sqrt(d.dt), sa = kAccelNoise * std::sqrt(d.dt);
  Eigen::Vector3d prev_dtheta = Eigen::Vector3d::Zero(), prev_dv = Eigen::Vector3d::Zero();
  for (int k = 0; k < n; ++k) {
    const double t0 = k * d.dt, t1 = t0 + d.dt;
    const Eigen::Quaterniond q0 = x.get<"theta">();
    const Eigen::Vector3d dtheta(0.0, 0.0, yaw_rate(t0) * d.dt);
    const Eigen::Quaterniond q1 = (q0 * so3::exp_quat(dtheta)).normalized();
    const Eigen::Vector3d v1 = q1 * Eigen::Vector3d(speed(t1), 0.0, 0.0);
    const double g = earth::normal_gravity(x.get<"p">()(0), x.get<"p">()(2));
    const Eigen::Vector3d dv = q0.conjugate() * (v1 - x.get<"v">() - Eigen::Vector3d(0.0, 0.0, g * d.dt));
    models::BodyIncrements exact;
    exact.dtheta = dtheta;
    exact.dv = dv;
    x = m.predict(x, exact, d.dt, nullptr);
    DriveStep s;
    s.t = t1;
    const Eigen::Vector3d gyro_noise = rng.normals<3>();
    const Eigen::Vector3d accel_noise = rng.normals<3>();
    s.imu.dtheta = dtheta + gyro_bias * d.dt + sg * gyro_noise;
    s.imu.dv = dv + accel_bias * d.dt + sa * accel_noise;
    s.imu.prev_dtheta = prev_dtheta;
    s.imu.prev_dv = prev_dv;
    s.imu.has_previous = k > 0;
    prev_dtheta = s.imu.dtheta;
    prev_dv = s.imu.dv;
    s.gyro_rate = s.imu.dtheta / d.dt;
    s.accel_rate = s.imu.dv / d.dt;
    s.truth = x;
    d.steps.push_back(s);
  }
  return d;
}

/// 10 m/s with a stop: decelerate over 5 s from `stop_at`, stand `stand` s, accelerate over 5 s.
inline double speed_with_stop(double t, double stop_at, double stand) {
  const double v = 10.0;
  if (t < stop_at) return v;
  if (t < stop_at + 5.0) return v * (1.0 - (t - stop_at) / 5.0);
  if (t < stop_at + 5.0 + stand) return 0.0;
  if (t < stop_at + 10.0 + stand) return v * (t - stop_at - 5.0 - stand) / 5.0;
  return v;
}

}  // namespace ctxfuse::test

// A simulated pedestrian or ground robot in a 20 m x 20 m yard, with the sensors a GNSS/INS
// recording of the real formats carries (written by sim/recording_writer.hpp as an RTKLIB .pos
// and an IMU csv + .tag, so that `ctxfuse run gins` reads it unchanged):
//   - pedestrian: at rest for rest_s with the device in the hand, then walking at 1.2 m/s round
//     a lap whose sides zig-zag (a 90 deg turn of 0.5 m radius every 3-4 m), standing for 5 s
//     after each lap; the device bobs 3 cm vertically at the step rate (2 Hz), sways 2 cm
//     sideways at half of it, and points away from the walking direction by up to 15 deg
//     (slow swings of the hand and a step-rate wobble: HeldDevice), so it slips sideways;
//   - robot: at rest for rest_s, then lawn-mower rows at 0.3 m/s (16 m rows, 1 m apart,
//     turned round on two 90 deg turns of 0.5 m radius), stopping for 3 s at each row's end.
// The IMU rides in the body frame (forward, right, down), samples at irregular steps (uniform
// in [step_min_s, step_max_s]) stamped by its own millisecond clock running rate_error_ppm
// fast; consumer MEMS errors (constant biases, white noise). GNSS at gnss_rate_hz, RTK fixed
// (1.5 cm) with float stretches (a 20 cm Gauss-Markov error) that report sigmas as small as a
// fixed solution's, as receivers do; Doppler velocity to 3 cm/s.
// Truth is the device's (= the IMU's = the antenna's) position, kept apart for scoring.
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "ctxfuse/core/error.hpp"
#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/models/earth.hpp"
#include "ctxfuse/sim/random.hpp"
#include "ctxfuse/sim/route.hpp"

namespace ctxfuse::sim {

enum class PlatformKind { pedestrian, robot };

struct PlatformRunConfig {
  PlatformKind kind = PlatformKind::pedestrian;
  std::uint64_t seed = 1;
  double rest_s = 12.0;        // at rest before moving off
  double duration_s = 300.0;   // the recording's length
  // IMU: irregular steps of its own clock (about 150 Hz for the walker's handheld device).
  double step_min_s = 0.006, step_max_s = 0.0085;
  double rate_error_ppm = 40.0;                  // the IMU clock's rate error (a crystal's tolerance)
  double gyro_noise_density = 0.01 * std::numbers::pi / 180.0;  // [rad/s/sqrt(Hz)] consumer MEMS
  double accel_noise_density = 150e-6 * kGravity;               // [m/s^2/sqrt(Hz)]
  double gyro_bias_sigma = 0.1 * std::numbers::pi / 180.0;      // [rad/s] turn-on bias
  double accel_bias_sigma = 0.01 * kGravity;                    // [m/s^2] (10 mg)
  // GNSS.
  double gnss_rate_hz = 4.0;
  double fixed_sigma_m = 0.015, float_sigma_m = 0.20, float_tau_s = 30.0;
  double float_share = 0.2;        // of the time, in stretches of float_stretch_s
  double float_stretch_s = 20.0;
  double velocity_sigma_mps = 0.03;
  double reported_sigma_m = 0.01;  // what the receiver claims, fixed or float
  Eigen::Vector3d origin_llh_deg = Eigen::Vector3d(37.4, -122.1, 30.0);
  double gps_start_s = 1780315200.0;  // 2026-06-01 12:00:00 on RTKLIB's 1970-based GPST scale

  SettingCheck check() const {
    auto pos = [](double v) { return std::isfinite(v) && v > 0.0; };
    if (!(std::isfinite(rest_s) && rest_s >= 0.0)) return SettingCheck::refuse("rest_s must be finite and >= 0");
    if (!pos(duration_s) || duration_s <= rest_s) return SettingCheck::refuse("duration_s must exceed rest_s");
    if (!pos(step_min_s) || !(step_max_s >= step_min_s)) return SettingCheck::refuse("IMU steps need 0 < step_min_s <= step_max_s");
    if (!(std::abs(rate_error_ppm) < 1000.0)) return SettingCheck::refuse("rate_error_ppm must be within +-1000");
    if (!pos(gnss_rate_hz) || gnss_rate_hz > 100.0) return SettingCheck::refuse("gnss_rate_hz must be in (0, 100]");
    if (!(float_share >= 0.0 && float_share < 1.0)) return SettingCheck::refuse("float_share must be in [0, 1)");
    if (!pos(float_stretch_s) || !pos(float_tau_s)) return SettingCheck::refuse("float stretches need positive lengths");
    return {};
  }
};

/// One IMU sample as the logger writes it: the IMU clock's tick and the body-frame (forward,
/// right, down) rates and specific force, with the true GPS time apart (for checks).
struct RecordedImuSample {
  double t_gps = 0.0;       // true time of the sample [s, GPST 1970 scale]
  std::int64_t tick_ms = 0; // the IMU clock, integer milliseconds
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();   // [rad/s] FRD
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();  // [m/s^2] FRD
};

struct PlatformRun {
  PlatformRunConfig config;
  std::vector<RecordedImuSample> imu;
  std::vector<messages::GnssFix> fixes;      // geodetic [deg, deg, m], covariances ENU, velocity ENU
  std::vector<messages::GnssFix> reference;  // truth at every GNSS epoch, RTK-fixed quality, 1 mm sigma
  double moving_off_s = 0.0;           // seconds after the start at which the platform moves
  /// The device's true path at 100 Hz: GPST [s] and ENU position [m] about the origin (the
  /// UWB site of sim/platform_recording.hpp ranges to it).
  std::vector<std::pair<double, Eigen::Vector3d>> path;
};

namespace detail {

inline Route platform_route(PlatformKind kind, double rest_s, double duration_s) {
  const double quarter = std::numbers::pi / 2.0;
  const double r = 0.5;
  Route route;
  std::vector<SpeedLeg> legs;
  if (kind == PlatformKind::pedestrian) {
    // A lap: four sides, each zig-zagging (4 m, left, 3 m, right, 4 m, right, 3 m, left, 4 m)
    // then a left corner: a 12 m square with 3 m bulges, inside the 20 m yard.
    PathBuilder b(Eigen::Vector2d(-6.0, -6.0), 0.0);
    const double lap_stop_s = 5.0;
    for (int lap = 0; lap < 8; ++lap) {
      for (int side = 0; side < 4; ++side) {
        b.straight(4.0).turn(quarter, r).straight(3.0).turn(-quarter, r).straight(4.0).turn(-quarter, r).straight(3.0)
            .turn(quarter, r).straight(4.0).turn(quarter, r);
      }
      legs.push_back({b.length(), 1.2, lap_stop_s});
    }
    route.path = b.build(0.2);
    route.phases = plan_speed(legs, rest_s, 1.0);
  } else {
    PathBuilder b(Eigen::Vector2d(-8.0, -8.0), 0.0);
    for (int row = 0; row < 16; ++row) {
      const double side = row % 2 == 0 ? 1.0 : -1.0;
      b.straight(16.0);
      legs.push_back({b.length(), 0.3, 3.0});
      b.turn(side * quarter, r).straight(0.5).turn(side * quarter, r);  // rows 1.5 m apart
      legs.push_back({b.length(), 0.3, 0.0});
    }
    route.path = b.build(0.1);
    route.phases = plan_speed(legs, rest_s, 0.3);
  }
  if (route.duration() < duration_s)
    throw std::invalid_argument("sim platform run: the route lasts " + std::to_string(route.duration()) + " s, less than " +
                                std::to_string(duration_s) + " s");
  return route;
}

/// The device's position [ENU] at t: the route's point, and for the walker the step bob and
/// sway (which vanish at rest).
inline Eigen::Vector3d device_position(const Route& route, PlatformKind kind, double t) {
  const KinematicState st = route.state_at(t);
  Eigen::Vector3d p = st.position;
  if (kind == PlatformKind::pedestrian && st.speed > 0.0) {
    // Two steps a second, the amplitude fading in and out with the speed.
    const double phase = 2.0 * std::numbers::pi * 2.0 * t;
    const double w = std::min(1.0, st.speed / 1.2);
    const Eigen::Vector3d left(-std::sin(st.yaw), std::cos(st.yaw), 0.0);
    p += w * (0.03 * std::sin(phase) * Eigen::Vector3d::UnitZ() + 0.02 * std::sin(0.5 * phase) * left);
  }
  return p;
}

/// How far the walker's device points from the walking direction [rad]: two slow swings of
/// the hand (amplitudes and periods drawn per run) and a 2 deg wobble at the step rate, all
/// fading with the speed (a standing walker holds the device still); zero for the robot.
struct HeldDevice {
  double a1 = 0.0, t1 = 1.0, p1 = 0.0, a2 = 0.0, t2 = 1.0, p2 = 0.0;
  double offset(const Route& route, PlatformKind kind, double t) const {
    if (kind != PlatformKind::pedestrian) return 0.0;
    const double w = std::min(1.0, route.state_at(t).speed / 1.2);
    const double two_pi = 2.0 * std::numbers::pi;
    return w * (a1 * std::sin(two_pi * t / t1 + p1) + a2 * std::sin(two_pi * t / t2 + p2) +
                2.0 * std::numbers::pi / 180.0 * std::sin(two_pi * 2.0 * t));
  }
};

}  // namespace detail

/// Simulates the run. Throws std::invalid_argument for a configuration outside its range.
inline PlatformRun simulate_platform_run(const PlatformRunConfig& c) {
  ctxfuse::detail::require_setting(c.check(), "sim platform run");
  const Route route = detail::platform_route(c.kind, c.rest_s, c.duration_s);
  PlatformRun run;
  run.config = c;
  run.moving_off_s = c.rest_s;
  const Eigen::Vector3d origin(c.origin_llh_deg(0) * std::numbers::pi / 180.0, c.origin_llh_deg(1) * std::numbers::pi / 180.0,
                               c.origin_llh_deg(2));
  auto llh_deg = [&](const Eigen::Vector3d& enu) {
    Eigen::Vector3d llh = earth::GeodeticRetraction::inject(origin, Eigen::Vector3d(enu.y(), enu.x(), -enu.z()));
    llh.head<2>() *= 180.0 / std::numbers::pi;
    return llh;
  };
  // Velocity and acceleration of the device by central differences of its position (1 ms):
  // the bob and sway included, exact to micrometres per second.
  const double h = 1e-3;
  auto pos = [&](double t) { return detail::device_position(route, c.kind, t); };
  auto vel = [&](double t) { return (pos(t + h) - pos(t - h)) / (2.0 * h); };
  auto acc = [&](double t) { return (pos(t + h) - 2.0 * pos(t) + pos(t - h)) / (h * h); };

  // The device's yaw: the route's and, in the hand, its offset from the walking direction.
  Rng hand(c.seed, Stream::speed);
  detail::HeldDevice held;
  held.a1 = hand.uniform(5.0, 10.0) * std::numbers::pi / 180.0;
  held.t1 = hand.uniform(15.0, 30.0);
  held.p1 = hand.uniform(0.0, 2.0 * std::numbers::pi);
  held.a2 = hand.uniform(2.0, 5.0) * std::numbers::pi / 180.0;
  held.t2 = hand.uniform(5.0, 10.0);
  held.p2 = hand.uniform(0.0, 2.0 * std::numbers::pi);
  auto yaw = [&](double t) { return route.state_at(t).yaw + held.offset(route, c.kind, t); };

  // IMU.
  Rng rng(c.seed, Stream::imu);
  Eigen::Vector3d bg, ba;
  for (int i = 0; i < 3; ++i) bg[i] = c.gyro_bias_sigma * rng.normal();
  for (int i = 0; i < 3; ++i) ba[i] = c.accel_bias_sigma * rng.normal();
  const double scale = 1.0 + c.rate_error_ppm * 1e-6;
  double t = h;  // the differences reach 1 ms before t
  double tick = 1000.0;
  while (t < c.duration_s - h) {
    const double dt = rng.uniform(c.step_min_s, c.step_max_s);
    // Body FLU from the device's yaw (the device level); FRD = (x, -y, -z).
    const double psi = yaw(t);
    const double cy = std::cos(psi), sy = std::sin(psi);
    const Eigen::Vector3d f_enu = acc(t) + Eigen::Vector3d(0.0, 0.0, kGravity);
    const Eigen::Vector3d f_flu(cy * f_enu.x() + sy * f_enu.y(), -sy * f_enu.x() + cy * f_enu.y(), f_enu.z());
    const Eigen::Vector3d w_flu(0.0, 0.0, std::remainder(yaw(t + h) - yaw(t - h), 2.0 * std::numbers::pi) / (2.0 * h));
    RecordedImuSample s;
    s.t_gps = c.gps_start_s + t;
    s.tick_ms = static_cast<std::int64_t>(std::floor(tick));
    const double gw = c.gyro_noise_density / std::sqrt(dt), aw = c.accel_noise_density / std::sqrt(dt);
    for (int i = 0; i < 3; ++i) {
      const double sign = i == 0 ? 1.0 : -1.0;
      s.gyro[i] = sign * w_flu[i] + bg[i] + gw * rng.normal();
      s.accel[i] = sign * f_flu[i] + ba[i] + aw * rng.normal();
    }
    run.imu.push_back(s);
    t += dt;
    tick += dt * 1000.0 * scale;
  }

  // GNSS: float stretches placed at random, a Gauss-Markov error while float.
  Rng g(c.seed, Stream::gnss);
  std::vector<std::pair<double, double>> floats;
  const int stretches = static_cast<int>(std::floor(c.float_share * c.duration_s / c.float_stretch_s));
  for (int k = 0; k < stretches; ++k) {
    const double start = g.uniform(0.0, c.duration_s - c.float_stretch_s);
    floats.emplace_back(start, start + c.float_stretch_s);
  }
  const GaussMarkov float_gm{c.float_sigma_m, c.float_tau_s};
  Eigen::Vector2d float_err(float_gm.start(g), float_gm.start(g));
  const double period = 1.0 / c.gnss_rate_hz;
  for (long k = 1;; ++k) {
    const double te = static_cast<double>(k) * period;
    if (te >= c.duration_s - h) break;
    bool is_float = false;
    for (const auto& [a, b] : floats) is_float = is_float || (te >= a && te < b);
    for (int i = 0; i < 2; ++i) float_err[i] = float_gm.step(float_err[i], period, g);
    const Eigen::Vector3d p = pos(te), v = vel(te);
    Eigen::Vector3d noise(c.fixed_sigma_m * g.normal(), c.fixed_sigma_m * g.normal(), 2.0 * c.fixed_sigma_m * g.normal());
    if (is_float) noise.head<2>() += float_err;
    messages::GnssFix f;
    f.t = c.gps_start_s + te;
    f.frame = messages::PositionFrame::geodetic;
    f.position = llh_deg(p + noise);
    f.cov = Eigen::Vector3d(c.reported_sigma_m, c.reported_sigma_m, 2.0 * c.reported_sigma_m).cwiseAbs2().asDiagonal();
    f.quality = is_float ? messages::FixQuality::floating : messages::FixQuality::fixed;
    f.satellites_used = 18;
    Eigen::Vector3d vn(c.velocity_sigma_mps * g.normal(), c.velocity_sigma_mps * g.normal(), c.velocity_sigma_mps * g.normal());
    f.velocity = v + vn;
    f.velocity_cov = Eigen::Matrix3d::Identity() * c.velocity_sigma_mps * c.velocity_sigma_mps;
    run.fixes.push_back(f);
    messages::GnssFix r = f;
    r.position = llh_deg(p);
    r.cov = Eigen::Matrix3d::Identity() * 1e-6;
    r.quality = messages::FixQuality::fixed;
    r.velocity = v;
    run.reference.push_back(r);
  }
  for (long k = 1;; ++k) {
    const double tp = static_cast<double>(k) * 0.01;
    if (tp >= c.duration_s - h) break;
    run.path.emplace_back(c.gps_start_s + tp, pos(tp));
  }
  return run;
}

}  // namespace ctxfuse::sim

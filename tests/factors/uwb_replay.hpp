// A 10-minute UWB replay for the pipeline's fixed-lag smoother (pipelines/nlos_uwb/smoother.hpp):
// a tag on a 20 m circle at 3 m/s inside 4 anchors (2 m high, tag at 1 m), one epoch of 4
// ranges every 0.1 s (6000 epochs), sigma 0.1 m, each range drawn afresh (no repeated noise);
// every 7th range is left out by the mask, so the slots change from epoch to epoch; and the
// circle's IMU for the smoother with IMU factors. Shared by the no-allocation tests
// (tests/factors) and bench_fixed_lag's replay benchmarks.
#pragma once

#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "ctxfuse/messages/sensors.hpp"
#include "ctxfuse/pipelines/nlos_uwb/smoother.hpp"
#include "ctxfuse/sim/random.hpp"

namespace ctxfuse::test {

struct UwbReplay {
  static constexpr double dt = 0.1, radius = 20.0, speed = 3.0;
  static constexpr int epochs_per_minute = 600;
  std::vector<std::array<messages::UwbRange, 4>> epochs;
  std::vector<std::array<bool, 4>> attach;

  explicit UwbReplay(int minutes = 10) {
    const std::array<Eigen::Vector3d, 4> anchors{Eigen::Vector3d(-30, -30, 2), Eigen::Vector3d(30, -30, 2), Eigen::Vector3d(30, 30, 2),
                                                 Eigen::Vector3d(-30, 30, 2)};
    sim::Rng rng(7, sim::Stream::uwb);
    const int n = minutes * epochs_per_minute;
    epochs.resize(static_cast<std::size_t>(n));
    attach.resize(static_cast<std::size_t>(n));
    for (int k = 0; k < n; ++k) {
      const double t = (k + 1) * dt, phi = speed * t / radius;
      const Eigen::Vector3d tag(radius * std::cos(phi), radius * std::sin(phi), 1.0);
      for (std::size_t a = 0; a < 4; ++a) {
        auto& r = epochs[static_cast<std::size_t>(k)][a];
        r.t = t;
        r.anchor_id = static_cast<int>(a);
        r.anchor_position = anchors[a];
        r.range_m = (anchors[a] - tag).norm() + 0.1 * rng.normal();
        attach[static_cast<std::size_t>(k)][a] = (4 * k + static_cast<int>(a)) % 7 != 0;
      }
    }
  }
  /// The pipeline's settings for this replay: its ranges are raw, one sample per report (what
  /// the self-calibrating EKF is told; the other estimators do not read it).
  static pipelines::nlos_uwb::Settings settings() {
    pipelines::nlos_uwb::Settings s;
    s.range_average_samples = 1;
    return s;
  }
  /// The start: the true position at t = 0 with 0.3 m sigma, velocity unknown (settings).
  Eigen::Vector2d start_position() const { return {radius, 0.0}; }
  Eigen::Matrix2d start_cov() const { return Eigen::Matrix2d::Identity() * 0.09; }

  /// The circle's IMU (body forward-left-up): yaw rate v / r, the centripetal v^2 / r to the
  /// left, gravity's reaction up; for the smoother with IMU factors (imu_smoother.hpp).
  static messages::ImuSample imu() {
    messages::ImuSample u;
    u.gyro = Eigen::Vector3d(0.0, 0.0, speed / radius);
    u.accel = Eigen::Vector3d(0.0, speed * speed / radius, 9.81);
    return u;
  }
  static Eigen::Vector2d on_circle(double t) {
    const double phi = speed * t / radius;
    return {radius * std::cos(phi), radius * std::sin(phi)};
  }
  /// Starts an IMU smoother by alignment from the true positions at the epochs' times; the
  /// index of the first epoch after the start (epochs.size() when it never starts).
  template <class S>
  std::size_t align(S& s) const {
    std::size_t k = 0;
    for (; k < epochs.size() && !s.started(); ++k) (void)s.start(epochs[k][0].t, on_circle(epochs[k][0].t), start_cov());
    return s.started() ? k : epochs.size();
  }
  /// The IMU in 10 ms pieces from imu_t to half an epoch past epoch k (the run loop sees an
  /// epoch only when the next range arrives, so the IMU is ahead of it).
  template <class S>
  void feed_imu(S& s, std::size_t k, double& imu_t) const {
    for (; imu_t < epochs[k][0].t + 0.5 * dt; imu_t += 0.01) s.add_imu(imu_t, 0.01, imu());
  }

  /// Epoch k through the smoother; false when the step is refused.
  template <class S>
  bool step(S& s, std::size_t k) const {
    std::array<Status, 4> st{};
    return s.apply_epoch(std::span<const messages::UwbRange>(epochs[k]), std::span<const bool>(attach[k]), std::span<Status>(st)).accepted();
  }
};

}  // namespace ctxfuse::test

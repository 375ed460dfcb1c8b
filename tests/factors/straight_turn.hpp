// A planar drive for the smoother tests: 20 s straight east at 5 m/s, a half turn to the
// left at 0.25 rad/s (radius 20 m, centripetal acceleration 1.25 m/s^2), then straight west,
// ranged at 10 Hz from 4 anchors at the corners of a 60 m square with sigma 0.1 m (a UWB
// line-of-sight figure). Noise from sim::Rng, which gives the same bytes with any compiler.
#pragma once

#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/sim/random.hpp"

namespace ctxfuse::test {

using PV2 = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;
using Range2 = models::RangeToPoint<PV2, 2>;
using Cv2 = models::ConstantVelocity<PV2, 2>;

struct DriveEpoch {
  double t = 0.0;
  Vector<4> truth = Vector<4>::Zero();
  std::array<double, 4> ranges{};
};

struct StraightTurnDrive {
  static constexpr double dt = 0.1;
  static constexpr double speed = 5.0;
  static constexpr double yaw_rate = 0.25;
  static constexpr double sigma = 0.1;
  static constexpr double centripetal = speed * yaw_rate;
  std::array<Vector<2>, 4> anchors{Vector<2>(-30, -30), Vector<2>(30, -30), Vector<2>(30, 30), Vector<2>(-30, 30)};
  std::vector<DriveEpoch> epochs;

  /// Constant velocity with q = a^2 dt: the velocity change of the turn over one epoch, a dt,
  /// as one standard deviation of the model's velocity noise sqrt(q dt) over that epoch.
  Cv2 motion() const {
    Cv2 cv;
    cv.accel_psd = centripetal * centripetal * dt;
    return cv;
  }
  Range2 range(int a) const {
    Range2 r;
    r.anchor = anchors[static_cast<std::size_t>(a)];
    r.sigma = sigma;
    return r;
  }

  explicit StraightTurnDrive(std::uint64_t seed, double duration = 50.0) {
    sim::Rng rng(seed, sim::Stream::uwb);
    const double t_turn = 20.0, t_end_turn = t_turn + std::numbers::pi / yaw_rate;
    const Vector<2> start(-25.0, -20.0);
    const double radius = speed / yaw_rate;
    for (int k = 0; k * dt <= duration + 1e-9; ++k) {
      DriveEpoch e;
      e.t = k * dt;
      Vector<2> p, v;
      if (e.t <= t_turn) {
        p = start + Vector<2>(speed * e.t, 0.0);
        v = Vector<2>(speed, 0.0);
      } else if (e.t <= t_end_turn) {
        const double psi = yaw_rate * (e.t - t_turn);
        const Vector<2> centre = start + Vector<2>(speed * t_turn, radius);
        p = centre + radius * Vector<2>(std::sin(psi), -std::cos(psi));
        v = speed * Vector<2>(std::cos(psi), std::sin(psi));
      } else {
        p = start + Vector<2>(speed * t_turn, 2.0 * radius) - Vector<2>(speed * (e.t - t_end_turn), 0.0);
        v = Vector<2>(-speed, 0.0);
      }
      e.truth << p, v;
      for (int a = 0; a < 4; ++a)
        e.ranges[static_cast<std::size_t>(a)] = (p - anchors[static_cast<std::size_t>(a)]).norm() + sigma * rng.normal();
      epochs.push_back(e);
    }
  }
};

}  // namespace ctxfuse::test

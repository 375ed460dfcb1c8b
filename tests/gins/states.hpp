// States and models shared by the gins tests.
#pragma once

#include "ctxfuse/models/ins_augment.hpp"
#include "ctxfuse/models/ins_nav.hpp"

namespace ctxfuse::test {

using Nav15 = models::InsNavModel<models::SimplifiedStrapdown>;
using Nav20 = models::Augmented<Nav15, StateBlock<"mount", 2>, StateBlock<"lever", 3>>;
using Nav16 = models::Augmented<Nav15, StateBlock<"speed_scale", 1>>;  // with an odometer's scale error

inline constexpr double kDeg = 3.14159265358979323846 / 180.0;

/// A state away from every special value (poles, zero rotation, zero biases).
inline models::NavState sample_nav_state() {
  models::NavState x;
  x.get<"p">() = Eigen::Vector3d(40.0 * kDeg, -86.0 * kDeg, 210.0);
  x.get<"v">() = Eigen::Vector3d(8.0, -3.0, 0.2);
  x.get<"theta">() = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, -0.3, 1.0).normalized()));
  x.get<"bg">() = Eigen::Vector3d(0.01, -0.02, 0.005);
  x.get<"ba">() = Eigen::Vector3d(0.1, -0.05, 0.2);
  return x;
}

inline Nav20::State sample_nav20_state() {
  Nav20::State x;
  Nav20::set_base_part(x, sample_nav_state());
  x.get<"mount">() = Eigen::Vector2d(-0.05, 0.09);
  x.get<"lever">() = Eigen::Vector3d(-1.2, 0.3, 0.6);
  return x;
}

inline Nav16::State sample_nav16_state() {
  Nav16::State x;
  Nav16::set_base_part(x, sample_nav_state());
  x.get<"speed_scale">() = Vector<1>(0.013);
  return x;
}

}  // namespace ctxfuse::test

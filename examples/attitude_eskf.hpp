// The core of examples/attitude_eskf.cpp: an error-state filter with a nominal state that is
// not a vector. The attitude is a unit quaternion, driven by a gyro whose bias the filter
// estimates, and corrected by two directions known in the world frame and measured in the body
// frame (gravity by an accelerometer at rest, magnetic north by a magnetometer).
// tests/examples/attitude_eskf_example_test.cpp checks the run against the same filter written
// out by hand with plain Eigen, and the model's Jacobians against central differences.
// docs/eskf.md walks through this file.
#pragma once

#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "ctxfuse/core/concepts.hpp"
#include "ctxfuse/core/so3.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/policies/gating.hpp"
#include "ctxfuse/sim/random.hpp"

namespace attitude_eskf {
using namespace ctxfuse;

// The nominal state: body-to-world rotation and gyro bias [rad/s].
struct Attitude {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();
};

// The error state, 6 elements: a rotation vector in the body frame (q_true = q * Exp(dtheta))
// and the bias error (b_true = b + db).
// Process model: q <- q * Exp((w - b) dt), b <- b, with w the gyro's reading (the Input).
struct GyroAttitude {
  static constexpr int dim = 6;
  using State = Attitude;
  using Input = Vector<3>;
  double gyro_noise_density = 1e-3;  // [rad/s/sqrt(Hz)]
  double bias_random_walk = 1e-5;    // [rad/s^2/sqrt(Hz)]

  State predict(const State& x, const Input& w, double dt, SquareMatrix<6>* F) const {
    const Vector<3> phi = (w - x.bias) * dt;
    State out = x;
    Eigen::Quaterniond dq;
    Eigen::Matrix3d Jr;
    so3::exp_quat_and_right_jacobian(phi, dq, Jr);
    out.q = (x.q * dq).normalized();
    if (F) {  // dtheta' = Exp(phi)' dtheta - Jr(phi) dt db
      F->setIdentity();
      F->topLeftCorner<3, 3>() = dq.toRotationMatrix().transpose();
      F->topRightCorner<3, 3>() = -Jr * dt;
    }
    return out;
  }
  SquareMatrix<6> noise(const State&, const Input&, double dt) const {
    SquareMatrix<6> Q = SquareMatrix<6>::Zero();
    Q.topLeftCorner<3, 3>().diagonal().setConstant(gyro_noise_density * gyro_noise_density * dt);
    Q.bottomRightCorner<3, 3>().diagonal().setConstant(bias_random_walk * bias_random_walk * dt);
    return Q;
  }
  // x [+] dx and its inverse a [-] b: what makes this an error-state model.
  State inject(const State& x, const Vector<6>& dx) const {
    return {(x.q * so3::exp_quat(dx.head<3>())).normalized(), x.bias + dx.tail<3>()};
  }
  Vector<6> difference(const State& a, const State& b) const {
    Vector<6> d;
    d << so3::log(b.q.conjugate() * a.q), a.bias - b.bias;
    return d;
  }
  // Optional: the covariance's reset after an injection, G = d(new error)/d(old error), to
  // first order in the injected rotation (the error is now about the corrected nominal).
  SquareMatrix<6> reset_jacobian(const State&, const Vector<6>& dx) const {
    SquareMatrix<6> G = SquareMatrix<6>::Identity();
    G.topLeftCorner<3, 3>() -= 0.5 * so3::skew(dx.head<3>());
    return G;
  }
};
static_assert(ErrorStateProcessModel<GyroAttitude>);

// A direction known in the world frame (unit vector `world`), measured in the body frame:
// z = R' world + noise. For a right perturbation, R' world changes by [R' world]x dtheta.
struct BodyDirection {
  static constexpr int dim = 3;
  Vector<3> world = Vector<3>::UnitZ();
  double sigma = 0.01;  // per component

  Vector<3> predict(const Attitude& x, Matrix<3, 6>* H) const {
    const Vector<3> body = x.q.conjugate() * world;
    if (H) {
      H->setZero();
      H->leftCols<3>() = so3::skew(body);
    }
    return body;
  }
  SquareMatrix<3> noise(const Attitude&) const { return SquareMatrix<3>::Identity() * sigma * sigma; }
};
static_assert(MeasurementModel<BodyDirection, Attitude, 6>);

using Filter = Eskf<GyroAttitude, policies::ChiSquareGate>;

struct Settings {
  std::uint64_t seed = 1;
  double duration_s = 60.0;
  double imu_dt = 0.01;             // 100 Hz gyro
  int steps_per_fix = 10;           // the directions at 10 Hz
  Vector<3> true_bias{0.01, -0.02, 0.015};  // [rad/s]
  double initial_error_deg = 5.0;   // about each axis
  double dip_deg = 60.0;            // magnetic inclination
};

struct Epoch {
  double t = 0.0;
  Vector<3> gyro;                  // the reading that predicted to t
  bool has_fix = false;
  Vector<3> up, north;             // the two measured directions, when has_fix
  Status predicted, up_updated, north_updated;
  eskf::Belief<GyroAttitude> belief;  // after the epoch's updates
  Vector<3> error;                 // the true attitude error: q_true = q * Exp(error)
  double error_deg = 0.0;          // its angle
};

struct Run {
  Settings settings;
  GyroAttitude model;
  BodyDirection up, north;
  eskf::Belief<GyroAttitude> initial;
  std::vector<Epoch> epochs;
};

inline Run run(const Settings& s = {}) {
  Run out;
  out.settings = s;
  const double dip = s.dip_deg * std::numbers::pi / 180.0;
  out.up.world = Vector<3>::UnitZ();
  out.up.sigma = 0.01;
  out.north.world = Vector<3>(std::cos(dip), 0.0, -std::sin(dip));
  out.north.sigma = 0.02;

  sim::Rng rng(s.seed);
  Eigen::Quaterniond truth = Eigen::Quaterniond::Identity();
  const double e0 = s.initial_error_deg * std::numbers::pi / 180.0;
  out.initial.nominal.q = truth * so3::exp_quat(Vector<3>(e0, -e0, e0));
  out.initial.cov.setZero();
  out.initial.cov.topLeftCorner<3, 3>().diagonal().setConstant(4.0 * e0 * e0);
  out.initial.cov.bottomRightCorner<3, 3>().diagonal().setConstant(0.03 * 0.03);
  Filter filter(out.model, out.initial, FilterOptions{}, policies::ChiSquareGate(0.999));

  const int steps = static_cast<int>(std::lround(s.duration_s / s.imu_dt));
  const double gyro_sigma = out.model.gyro_noise_density / std::sqrt(s.imu_dt);
  out.epochs.reserve(static_cast<std::size_t>(steps));
  for (int k = 1; k <= steps; ++k) {
    Epoch e;
    e.t = k * s.imu_dt;
    const double tm = e.t - 0.5 * s.imu_dt;  // the body turns at this rate over the step
    const Vector<3> rate(0.3 * std::sin(0.5 * tm), 0.2 * std::cos(0.3 * tm), 0.5);
    truth = (truth * so3::exp_quat(rate * s.imu_dt)).normalized();
    e.gyro = rate + s.true_bias + gyro_sigma * rng.normals<3>();
    e.predicted = filter.predict(e.gyro, s.imu_dt);
    if (k % s.steps_per_fix == 0) {
      e.has_fix = true;
      e.up = truth.conjugate() * out.up.world + out.up.sigma * rng.normals<3>();
      e.north = truth.conjugate() * out.north.world + out.north.sigma * rng.normals<3>();
      e.up_updated = filter.update(out.up, e.up);
      e.north_updated = filter.update(out.north, e.north);
    }
    e.belief = filter.belief();
    e.error = so3::log(filter.nominal().q.conjugate() * truth);
    e.error_deg = e.error.norm() * 180.0 / std::numbers::pi;
    out.epochs.push_back(e);
  }
  return out;
}

}  // namespace attitude_eskf

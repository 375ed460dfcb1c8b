// The filter the gins tests run over a simulated drive (drive_sim.hpp): GNSS position at 1 Hz
// outside an outage, and the constraints that are switched on -- ZUPT and ZIHR while the raw
// IMU says static, NHC while moving, the magnetometer's relative heading from the outage start
// -- each with a chi-square gate. Noise settings from the same data-sheet figures as the
// simulated IMU; constraint sigmas from what the truth obeys (NHC and ZUPT hold exactly in the
// simulation, 0.05 m/s is a car's suspension-level violation).
#pragma once

#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/models/ins_motion.hpp"
#include "ctxfuse/models/ins_updates.hpp"
#include "drive_sim.hpp"

namespace ctxfuse::test {

struct Constraints {
  bool zupt = false, zihr = false, nhc = false, mag = false;
};

struct DriveResult {
  double horizontal_error = 0.0;  // [m] at the outage's end
  double heading_error = 0.0;     // [rad] at the outage's end
  int gated = 0;
};

template <class Model>
Model drive_model() {
  Model m;
  models::InsNavModel<>* nav = nullptr;
  if constexpr (requires { m.base; }) nav = &m.base; else nav = &m;
  nav->gyro_noise_density = kGyroNoise;
  nav->accel_noise_density = kAccelNoise;
  nav->gyro_bias = models::GaussMarkov{3.8e-5 * kDeg};
  nav->accel_bias = models::GaussMarkov{7e-6 * 9.80665};
  return m;
}

template <class Model>
const models::NavState nav_part(const typename Model::State& x) {
  if constexpr (requires { Model::base_part(x); }) return Model::base_part(x); else return x;
}

template <class Model>
eskf::Belief<Model> drive_prior(const Drive& d) {
  eskf::Belief<Model> b;
  if constexpr (requires { Model::set_base_part(b.nominal, d.start); }) Model::set_base_part(b.nominal, d.start);
  else b.nominal = d.start;
  b.cov.setZero();
  Vector<15> sd;
  sd << 1, 1, 1, 0.1, 0.1, 0.1, kDeg, kDeg, 2 * kDeg, 0.05 * kDeg, 0.05 * kDeg, 0.05 * kDeg, 0.03, 0.03, 0.03;
  b.cov.template topLeftCorner<15, 15>() = sd.cwiseAbs2().asDiagonal();
  return b;
}

/// Runs the filter over the drive; GNSS withheld in [outage_start, outage_end).
template <class Model>
DriveResult run_drive(const Drive& d, const Model& model, eskf::Belief<Model>& b, const Constraints& c,
                      double outage_start, double outage_end, std::uint64_t seed) {
  using S = typename Model::State;
  sim::Rng rng(seed, sim::Stream::gnss);
  sim::Rng mag_rng(seed, sim::Stream::magnetometer);
  const policies::ChiSquareGate gate(0.999);
  models::StaticDetector detector;
  models::GnssGeodeticPosition<S> gnss;
  const double gnss_sigma = 0.5;
  models::ZeroVelocity<S> zupt;
  models::Heading<S> zihr;
  zihr.sigma = 0.1 * kDeg;
  models::NonHolonomic<S> nhc;
  nhc.sigma = 0.05;
  models::Heading<S> mag_heading;
  mag_heading.sigma = 2.0 * kDeg;
  models::MagRelativeHeading mag;
  const Eigen::Vector3d field_ned(22.0, 5.0, 42.0);  // [uT]
  const double mag_noise = 0.3;                        // [uT]
  double held_heading = 0.0;
  DriveResult r;
  auto count = [&](const Status& s) { r.gated += s.outcome == Outcome::gated ? 1 : 0; };
  for (std::size_t k = 0; k < d.steps.size(); ++k) {
    const DriveStep& s = d.steps[k];
    if (!eskf::predict(model, b, s.imu, d.dt).accepted()) return {1e9, 1e9, -1};
    const bool is_static = detector.push(s.t, s.gyro_rate, s.accel_rate);
    const bool in_outage = s.t >= outage_start && s.t < outage_end;
    const bool tenth = k % 10 == 9;
    const Eigen::Matrix3d C = nav_part<Model>(b.nominal).template get<"theta">().toRotationMatrix();
    if (!in_outage && k % 100 == 99) {
      const Eigen::Vector3d llh = s.truth.template get<"p">();
      gnss.R = models::geodetic_position_noise(llh, Eigen::Matrix3d::Identity() * gnss_sigma * gnss_sigma);
      const Eigen::Vector3d noise = rng.normals<3>();
      count(eskf::update(model, gnss, b, earth::GeodeticRetraction::inject(llh, gnss_sigma * noise), gate));
    }
    if (c.zihr && detector.entered_static()) held_heading = models::heading_of(C);
    if (tenth && is_static) {
      if (c.zupt) count(eskf::update(model, zupt, b, Vector<3>::Zero(), gate));
      if (c.zihr) count(eskf::update(model, zihr, b, Vector<1>(held_heading), gate));
    }
    if (tenth && !is_static && c.nhc) {
      nhc.vehicle.gyro = s.gyro_rate;
      count(eskf::update(model, nhc, b, Vector<2>::Zero(), gate));
    }
    if (c.mag && tenth && s.t >= outage_start) {
      const Eigen::Vector3d field_body = s.truth.template get<"theta">().conjugate() * field_ned +
                                         mag_noise * Eigen::Vector3d(mag_rng.normal(), mag_rng.normal(), mag_rng.normal());
      if (!mag.active()) {
        mag.start(C, field_body);
      } else if (const auto z = mag.heading(C, field_body)) {
        count(eskf::update(model, mag_heading, b, Vector<1>(*z), gate));
      }
    }
    if (s.t >= outage_end - 1e-9 && s.t < outage_end + d.dt - 1e-9) {
      const Vector<15> e = Nav15{}.difference(nav_part<Model>(b.nominal), s.truth);
      r.horizontal_error = e.head<2>().norm();
      r.heading_error = std::abs(PlanarAngleRetraction::wrap(
          models::heading_of(C) - models::heading_of(s.truth.template get<"theta">().toRotationMatrix())));
    }
  }
  return r;
}

// Compiled once, in drive_filter.cpp, for the two layouts the tests run (each instance costs
// g++ some 30 s of CPU).
extern template DriveResult run_drive<Nav15>(const Drive&, const Nav15&, eskf::Belief<Nav15>&, const Constraints&, double,
                                             double, std::uint64_t);
extern template DriveResult run_drive<Nav20>(const Drive&, const Nav20&, eskf::Belief<Nav20>&, const Constraints&, double,
                                             double, std::uint64_t);

}  // namespace ctxfuse::test

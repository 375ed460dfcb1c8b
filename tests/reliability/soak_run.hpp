// The soak's simulation and run loop (soak.hpp says what is checked and why).
#pragma once

#include <array>
#include <optional>

#include "ins_sim.hpp"
#include "soak.hpp"

namespace ctxfuse::reliability::soak {
namespace detail {

using InsModel = models::InsNavModel<models::FullStrapdown>;
using Nav = InsModel::State;
namespace rimm = pipelines::region_imm;
using ImmMixing = policies::FixedTransition<3>;

inline constexpr int kRate = 100;  // IMU epochs per second
inline constexpr double kDt = 1.0 / kRate;

/// The data-sheet figures of the gins drive (tests/gins/drive_sim.hpp): gyro 0.0038 deg/s/sqrt(Hz),
/// accelerometer 70 ug/sqrt(Hz), bias random walks 3.8e-5 deg/s/sqrt(s) and 7 ug/sqrt(s).
inline InsModel ins_model() {
  InsModel m;
  m.gyro_noise_density = 0.0038 * kDeg;
  m.accel_noise_density = 70e-6 * 9.80665;
  m.gyro_bias = models::GaussMarkov{3.8e-5 * kDeg};
  m.accel_bias = models::GaussMarkov{7e-6 * 9.80665};
  return m;
}

/// The geodetic truth: NED heading pi/2 - the track's ENU heading, level attitude.
struct InsTruth {
  InsModel m = ins_model();
  Nav x;
  double h0 = 520.0;
  models::BodyIncrements prev_clean, prev_measured;
  bool started = false;

  static Eigen::Quaterniond attitude(double t) {
    return Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * kPi - Track::heading_enu(t), Eigen::Vector3d::UnitZ()));
  }
  static Eigen::Vector3d velocity(double t) {
    const double psi = Track::heading_enu(t);
    return Track::speed(t) * Eigen::Vector3d(std::sin(psi), std::cos(psi), 0.0);
  }
  InsTruth() {
    x.get<"p">() = Eigen::Vector3d(48.1 * kDeg, 11.6 * kDeg, h0);
    x.get<"v">() = velocity(0.0);
    x.get<"theta">() = attitude(0.0);
  }

  /// One step from t: moves the truth, returns the measured increments.
  models::BodyIncrements step(double t, sim::Rng& rng) {
    const Eigen::Vector3d llh = x.get<"p">(), v = x.get<"v">();
    const Eigen::Quaterniond q = x.get<"theta">();
    const Eigen::Vector3d w_ie = earth::earth_rate_ned(llh(0)), w_en = earth::transport_rate_ned(llh(0), llh(2), v);
    models::BodyIncrements clean;
    // The increments that make the mechanisation reach the target at t + dt (less its second-
    // order rotation terms, which the next step's feedback takes out).
    clean.dtheta = so3::log(Eigen::Quaterniond(q.conjugate() * so3::exp_quat(Eigen::Vector3d((w_ie + w_en) * kDt)) *
                                               attitude(t + kDt))) +
                   x.get<"bg">() * kDt;
    Eigen::Vector3d v_target = velocity(t + kDt);
    v_target(2) = 0.01 * (llh(2) - h0);  // hold the height
    const Eigen::Vector3d dv_n = v_target - v - Eigen::Vector3d(0.0, 0.0, earth::normal_gravity(llh(0), llh(2)) * kDt) +
                                 (2.0 * w_ie + w_en).cross(v) * kDt;
    clean.dv = q.conjugate() * dv_n + x.get<"ba">() * kDt;
    models::BodyIncrements measured = clean;
    measured.dtheta += m.gyro_noise_density * std::sqrt(kDt) * rng.normals<3>();
    measured.dv += m.accel_noise_density * std::sqrt(kDt) * rng.normals<3>();
    chain(clean, prev_clean, !started);
    chain(measured, prev_measured, !started);
    started = true;
    x = m.predict(x, clean, kDt, nullptr);
    walk_biases(m, x, kDt, rng);
    return measured;
  }
};

/// The planar truth of the region pipeline's model (ENU position, velocity, heading, yaw-rate
/// and accelerometer biases), white noise and bias walks of the pipeline's Settings.
struct PlanarTruth {
  using L = models::PlanarLayout;
  models::PlanarImuModel m;
  Vector<L::size> x = Vector<L::size>::Zero();

  explicit PlanarTruth(const rimm::Settings& s) : m(rimm::process_model(s, 1.0)) {}

  models::PlanarImu step(double t, sim::Rng& rng) {
    const double psi = L::get<"psi">(x)(0), psi_next = Track::heading_enu(t + kDt);
    const Vector<2> v_next = Track::speed(t + kDt) * Vector<2>(std::cos(psi_next), std::sin(psi_next));
    const Vector<2> a = (v_next - L::get<"v">(x)) / kDt;
    models::PlanarImu clean;
    clean.yaw_rate = models::wrap_angle(psi_next - psi) / kDt + L::get<"bg">(x)(0);
    clean.accel = Eigen::Rotation2Dd(psi).inverse() * a + L::get<"ba">(x);
    models::PlanarImu measured = clean;
    measured.yaw_rate += m.gyro_noise_density / std::sqrt(kDt) * rng.normal();
    for (int i = 0; i < 2; ++i) measured.accel(i) += m.accel_noise_density / std::sqrt(kDt) * rng.normal();
    x = m.predict(x, clean, kDt, nullptr);
    L::get<"bg">(x)(0) += m.gyro_bias_walk * std::sqrt(kDt) * rng.normal();
    for (int i = 0; i < 2; ++i) L::get<"ba">(x)(i) += m.accel_bias_walk * std::sqrt(kDt) * rng.normal();
    return measured;
  }
};

/// Counts the IMM's GNSS updates and those the IMM as a whole gated (its last taker).
struct GateCounter {
  std::size_t updates = 0, gated = 0;
  void operator()(const rimm::UpdateEvent& e) {
    ++updates;
    gated += e.gated[static_cast<std::size_t>(e.takers - 1)] ? 1 : 0;
  }
};

inline void add_time(FilterReport& r, std::size_t bucket, double ns, std::vector<std::size_t>& steps) {
  if (r.bucket_ns_per_step.size() <= bucket) r.bucket_ns_per_step.resize(bucket + 1, 0.0);
  if (steps.size() <= bucket) steps.resize(bucket + 1, 0);
  r.bucket_ns_per_step[bucket] += ns;
  steps[bucket] += kRate;
}

}  // namespace detail

/// Runs the soak; `progress` (may be empty) is called after every bucket of simulated time.
inline Report run(const Config& c, const std::function<void(const Report&, std::size_t)>& progress = {}) {
  using namespace detail;
  Report rep;
  sim::Rng rng(c.seed, sim::Stream::imu), gnss_rng(c.seed, sim::Stream::gnss);

  // GNSS/INS filter, started on the truth with the gins tests' prior.
  InsTruth ins_truth;
  const InsModel ins = ins_model();
  eskf::Belief<InsModel> b;
  b.nominal = ins_truth.x;
  Vector<15> sd;
  sd << 1, 1, 1, 0.1, 0.1, 0.1, kDeg, kDeg, 2 * kDeg, 0.05 * kDeg, 0.05 * kDeg, 0.05 * kDeg, 0.03, 0.03, 0.03;
  b.cov = sd.cwiseAbs2().asDiagonal();
  models::GnssGeodeticPosition<Nav> fix;
  fix.lever_arm = Eigen::Vector3d(0.5, 0.0, -1.0);
  const policies::ChiSquareGate gate(0.999);

  // The region pipeline's plain IMM with its default settings.
  const rimm::Settings s;
  PlanarTruth planar(s);
  GateCounter counter;
  rimm::Aided<rimm::ImmCore<ImmMixing>> imm(
      rimm::ImmCore<ImmMixing>{&s, rimm::detail::make_mixing<ImmMixing>(s), nullptr}, s, &counter);
  {
    Gaussian<8> b0;
    b0.mean = planar.x;
    Vector<8> psd;
    psd << s.init_position_sigma, s.init_position_sigma, s.init_velocity_sigma, s.init_velocity_sigma,
        s.init_heading_sigma_deg * kDeg, s.init_gyro_bias_sigma, s.init_accel_bias_sigma, s.init_accel_bias_sigma;
    b0.cov = psd.cwiseAbs2().asDiagonal();
    imm.start(0.0, b0);
  }
  auto check_modes = [&] {
    const auto& f = *imm.core().f;
    check(rep.imm, f.template mode_belief<0>().mean.allFinite(), f.template mode_belief<0>().cov);
    check(rep.imm, f.template mode_belief<1>().mean.allFinite(), f.template mode_belief<1>().cov);
    check(rep.imm, f.template mode_belief<2>().mean.allFinite(), f.template mode_belief<2>().cov);
  };

  std::array<models::BodyIncrements, kRate> ins_u;
  std::array<Nav, kRate> ins_x;
  std::array<models::PlanarImu, kRate> planar_u;
  std::array<Vector<8>, kRate> planar_x;
  std::vector<std::size_t> ins_steps, imm_steps;
  const auto seconds = static_cast<long>(c.seconds);
  for (long sec = 0; sec < seconds; ++sec) {
    const double t0 = static_cast<double>(sec), t1 = t0 + 1.0;
    const bool outage = in_outage(c, t0);
    const auto bucket = static_cast<std::size_t>(t0 / c.bucket_s);
    for (int k = 0; k < kRate; ++k) {
      const double t = t0 + k * kDt;
      ins_u[static_cast<std::size_t>(k)] = ins_truth.step(t, rng);
      ins_x[static_cast<std::size_t>(k)] = ins_truth.x;
      planar_u[static_cast<std::size_t>(k)] = planar.step(t, rng);
      planar_x[static_cast<std::size_t>(k)] = planar.x;
    }
    // The fixes at t1 (drawn whether or not an outage withholds them: the same noise either way).
    const Eigen::Vector3d antenna = fix.predict(ins_x.back(), nullptr);
    const Vector<3> z_ins = earth::GeodeticRetraction::inject(antenna, c.gnss_sigma * gnss_rng.normals<3>());
    messages::GnssFix planar_fix;
    planar_fix.t = t1;
    Vector<2> n;  // drawn in index order, so that g++ and clang run the same soak
    for (int i = 0; i < 2; ++i) n(i) = gnss_rng.normal();
    planar_fix.position.head<2>() = models::PlanarLayout::get<"p">(planar_x.back()) + c.gnss_sigma * n;
    planar_fix.cov = Eigen::Matrix3d::Identity() * c.gnss_sigma * c.gnss_sigma;

    double start = thread_cpu_ns();
    for (int k = 0; k < kRate; ++k) {
      const auto i = static_cast<std::size_t>(k);
      if (!eskf::predict(ins, b, ins_u[i], kDt).accepted()) ++rep.ins.refused;
      check(rep.ins, ins.is_finite(b.nominal), b.cov);
      const bool at_fix = k == kRate - 1;
      if (at_fix && !outage) {
        fix.R = models::geodetic_position_noise(z_ins, Eigen::Matrix3d::Identity() * c.gnss_sigma * c.gnss_sigma);
        const Status st = eskf::update(ins, fix, b, z_ins, gate);
        ++rep.ins.updates;
        if (st.outcome == Outcome::gated) ++rep.ins.gated;
        else if (!st.accepted()) ++rep.ins.refused;
        check(rep.ins, ins.is_finite(b.nominal), b.cov);
      }
      note(rep.ins, c, bucket, t0 + (k + 1) * kDt, ins.difference(b.nominal, ins_x[i]).head<2>(),
           b.cov.topLeftCorner<2, 2>(), at_fix && !outage);
    }
    add_time(rep.ins, bucket, thread_cpu_ns() - start, ins_steps);

    start = thread_cpu_ns();
    for (int k = 0; k < kRate; ++k) {
      const double t = t0 + (k + 1) * kDt;
      imm.predict(planar_u[static_cast<std::size_t>(k)], kDt);
      check_modes();
      if ((k + 1) % 10 == 0) imm.speed(messages::SpeedSample{t, Track::speed(t)});
    }
    if (!outage) imm.gnss(planar_fix);
    imm.epoch(t1);
    check_modes();
    const Gaussian<8> out = imm.core().f->combined();
    check(rep.imm, out.mean.allFinite(), out.cov);
    add_time(rep.imm, bucket, thread_cpu_ns() - start, imm_steps);
    using PL = models::PlanarLayout;
    note(rep.imm, c, bucket, t1, PL::get<"p">(out.mean) - PL::get<"p">(planar_x.back()), PL::cov<"p">(out.cov), !outage);

    rep.ins.steps += kRate;
    rep.imm.steps += kRate;
    rep.seconds = t1;
    const bool bucket_done = sec + 1 == seconds || static_cast<std::size_t>(t1 / c.bucket_s) != bucket;
    if (bucket_done) {
      rep.ins.bucket_ns_per_step[bucket] /= static_cast<double>(ins_steps[bucket]);
      rep.imm.bucket_ns_per_step[bucket] /= static_cast<double>(imm_steps[bucket]);
      if (progress) progress(rep, bucket);
    }
  }
  rep.imm.updates = counter.updates;
  rep.imm.gated = counter.gated;
  rep.imm.refused += imm.track().rejected_imu;
  return rep;
}

}  // namespace ctxfuse::reliability::soak

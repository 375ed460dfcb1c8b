// A loosely coupled INS/GNSS error-state filter on the simulated indoor/outdoor drive: the
// 15-state strapdown model driven by the 100 Hz IMU, corrected by GNSS fixes behind a
// chi-square gate. Indoors there are no fixes, so the example also shows how fast a MEMS INS
// drifts once GNSS is gone -- the reason the region-aware pipeline brings in UWB there.
//   build/release/examples/example_ins_gnss_eskf [seed]
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "ctxfuse/ctxfuse.hpp"
#include "ctxfuse/sim/drive.hpp"

int main(int argc, char** argv) {
  using namespace ctxfuse;
  sim::DriveConfig config;
  config.seed = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 1;
  const sim::Drive drive = sim::simulate_drive(config);

  // Noise figures of the simulated IMU (sim/config.hpp), inflated a little for the model's
  // simplifications (no scale-factor states).
  models::Ins15Model model;  // ENU gravity by default, as the simulator
  model.gyro_noise_density = 2.0 * config.imu.gyro_noise_density;
  model.accel_noise_density = 2.0 * config.imu.accel_noise_density;
  model.gyro_bias = {config.imu.gyro_bias_sigma * std::sqrt(2.0 / config.imu.gyro_bias_tau_s), config.imu.gyro_bias_tau_s};
  model.accel_bias = {config.imu.accel_bias_sigma * std::sqrt(2.0 / config.imu.accel_bias_tau_s), config.imu.accel_bias_tau_s};

  // Initialise from the first truth sample with a metre and a few degrees of uncertainty.
  const sim::TruthSample& t0 = drive.truth.front();
  eskf::Belief<models::Ins15Model> belief;
  belief.nominal.p = t0.position;
  belief.nominal.v = t0.velocity;
  belief.nominal.q = Eigen::AngleAxisd(t0.yaw, Eigen::Vector3d::UnitZ()) *
                     Eigen::AngleAxisd(t0.pitch, Eigen::Vector3d::UnitY()) *
                     Eigen::AngleAxisd(t0.roll, Eigen::Vector3d::UnitX());
  belief.cov.setZero();
  using L = models::Ins15Layout;
  L::cov<"p">(belief.cov).diagonal().setConstant(1.0);
  L::cov<"v">(belief.cov).diagonal().setConstant(0.1);
  L::cov<"theta">(belief.cov).diagonal().setConstant(std::pow(3.0 * M_PI / 180.0, 2));
  L::cov<"bg">(belief.cov).diagonal().setConstant(std::pow(config.imu.gyro_bias_sigma, 2));
  L::cov<"ba">(belief.cov).diagonal().setConstant(std::pow(config.imu.accel_bias_sigma, 2));
  Eskf<models::Ins15Model, policies::ChiSquareGate> filter(model, belief, {}, policies::ChiSquareGate(0.999));
  filter.set_time(drive.imu.front().t);

  double sq_err[3] = {0, 0, 0};
  int count[3] = {0, 0, 0}, accepted = 0, gated = 0;
  std::size_t next_fix = 0, truth_index = 0;
  for (const sim::ImuSample& s : drive.imu) {
    if (s.t <= filter.time()) continue;
    // GNSS fixes up to this IMU time are applied at their own epoch (predict to it first).
    for (; next_fix < drive.gnss.size() && drive.gnss[next_fix].t <= s.t; ++next_fix) {
      const sim::GnssEpoch& e = drive.gnss[next_fix];
      if (!e.has_fix || e.t <= filter.time()) continue;
      // A fix is applied at its own epoch only: if the prediction to it is refused, skip it.
      if (!filter.predict_to(e.t, s)) continue;
      models::GnssPosition<> fix;
      fix.R = Vector<3>(e.std_horizontal_m * e.std_horizontal_m, e.std_horizontal_m * e.std_horizontal_m,
                        e.std_vertical_m * e.std_vertical_m).asDiagonal();
      const Status st = filter.update(fix, e.position);
      accepted += st.accepted();
      gated += st.outcome == Outcome::gated;
    }
    if (!filter.predict_to(s.t, s)) continue;
    while (truth_index + 1 < drive.truth.size() && drive.truth[truth_index].t < s.t) ++truth_index;
    const sim::TruthSample& truth = drive.truth[truth_index];
    const double e2 = (filter.nominal().p - truth.position).head<2>().squaredNorm();
    const auto r = static_cast<std::size_t>(truth.region);
    sq_err[r] += e2;
    ++count[r];
  }
  std::printf("INS/GNSS ESKF on the simulated drive (seed %llu): %d fixes accepted, %d gated\n",
              static_cast<unsigned long long>(config.seed), accepted, gated);
  const char* names[3] = {"outdoor", "transition", "indoor (no GNSS)"};
  for (int r = 0; r < 3; ++r)
    std::printf("  horizontal RMS error, %-17s %8.2f m\n", names[r], count[r] ? std::sqrt(sq_err[r] / count[r]) : NAN);
  return 0;
}

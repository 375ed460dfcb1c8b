// An error-state Kalman filter on a quaternion: attitude and gyro bias from a 100 Hz gyro,
// corrected at 10 Hz by gravity and magnetic north measured in the body frame. docs/eskf.md
// explains it.
//   build/release/examples/example_attitude_eskf [seed]
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "attitude_eskf.hpp"

int main(int argc, char** argv) {
  attitude_eskf::Settings s;
  if (argc > 1) s.seed = std::strtoull(argv[1], nullptr, 10);
  const attitude_eskf::Run r = attitude_eskf::run(s);

  std::printf("attitude ESKF, seed %llu: gyro %.0f Hz, gravity and north %.0f Hz, %.0f s\n",
              static_cast<unsigned long long>(s.seed), 1.0 / s.imu_dt, 1.0 / (s.imu_dt * s.steps_per_fix), s.duration_s);
  std::printf("    t_s  error_deg  sigma_deg   bias_x    bias_y    bias_z [deg/s]\n");
  const double deg = 180.0 / M_PI;
  int accepted = 0, fixes = 0;
  for (const auto& e : r.epochs) {
    if (e.has_fix) {
      fixes += 2;
      accepted += e.up_updated.accepted() + e.north_updated.accepted();
    }
    const long ms = std::lround(e.t * 1000.0);
    if (ms != 10 && ms != 100 && ms != 1000 && ms % 10000 != 0) continue;
    const double sigma = std::sqrt(e.belief.cov.topLeftCorner<3, 3>().trace() / 3.0) * deg;
    const auto& b = e.belief.nominal.bias;
    std::printf("%7.2f  %9.3f  %9.3f  %8.4f  %8.4f  %8.4f\n", e.t, e.error_deg, sigma, b.x() * deg, b.y() * deg,
                b.z() * deg);
  }
  std::printf("true bias                         %8.4f  %8.4f  %8.4f\n", s.true_bias.x() * deg, s.true_bias.y() * deg,
              s.true_bias.z() * deg);
  std::printf("direction updates accepted: %d of %d\n", accepted, fixes);
  return 0;
}

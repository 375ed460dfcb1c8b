// A simulated platform run (sim/platform_run.hpp) written as a GNSS/INS recording in the real
// formats, the layout `ctxfuse run gins` reads:
//   DIR/gnss.pos              the receiver's solutions (RTKLIB .pos, with velocity)
//   DIR/imu.csv, imu.csv.tag  the IMU's samples by its own clock's ticks, and the time tags
//   DIR/reference/truth.pos   the truth at every GNSS epoch, apart from the recording (for
//                             `run gins --reference`); a sub-folder, so the recording holds
//                             exactly one .pos
//   DIR/uwb/A<id>.csv         a UWB site in the Hanyang layout (sim/uwb_site.hpp): 8 anchors
//   DIR/uwb/trajectory.csv    round the 20 m yard at 0.5 and 2 m, 100 Hz raw ranges with
//                             per-anchor biases of 0.10-0.30 m, the device held 1 m above the
//                             ground; its reference (`run uwb --data DIR/uwb`)
// The IMU is in body axes (forward, right, down): the installation is the identity.
#pragma once

#include <filesystem>
#include <span>
#include <vector>

#include "ctxfuse/io/imu_tag_write.hpp"
#include "ctxfuse/io/rtklib_pos.hpp"
#include "ctxfuse/io/hanyang_uwb.hpp"
#include "ctxfuse/sim/platform_run.hpp"
#include "ctxfuse/sim/uwb_site.hpp"

namespace ctxfuse::sim {

/// Writes the recording into `dir` (created when missing). Throws what the writers throw.
inline void write_platform_recording(const PlatformRun& run, const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  fs::create_directories(dir / "reference");
  io::write_rtklib_pos(dir / "gnss.pos", std::span<const messages::GnssFix>(run.fixes));
  io::write_rtklib_pos(dir / "reference" / "truth.pos", std::span<const messages::GnssFix>(run.reference));
  std::vector<messages::ImuSample> samples;
  std::vector<std::int64_t> ticks;
  samples.reserve(run.imu.size());
  ticks.reserve(run.imu.size());
  for (const auto& s : run.imu) {
    samples.push_back({s.t_gps, s.gyro, s.accel, false});
    ticks.push_back(s.tick_ms);
  }
  const double start = run.imu.empty() ? run.config.gps_start_s : run.imu.front().t_gps;
  io::write_imu_csv_and_tag(dir / "imu.csv", std::span<const messages::ImuSample>(samples), std::span<const std::int64_t>(ticks), start);

  // The UWB site: the device 1 m above the ground (the Hanyang protocol's tag height).
  constexpr double kTagHeight = 1.0;
  std::vector<PositionSample> path;
  path.reserve(run.path.size());
  for (const auto& [t, p] : run.path) path.push_back({t, p + Eigen::Vector3d(0.0, 0.0, kTagHeight)});
  UwbSiteConfig site;
  const double xy[8][2] = {{-10, -10}, {0, -10}, {10, -10}, {10, 0}, {10, 10}, {0, 10}, {-10, 10}, {-10, 0}};
  for (int k = 0; k < 8; ++k)
    site.anchors.push_back({k + 1, Eigen::Vector3d(xy[k][0], xy[k][1], k % 2 ? 2.0 : 0.5), 100.0, 0.0005 * k, 0.10 + 0.2 * k / 7.0});
  site.rate_jitter_s = 0.0003;
  site.seed = run.config.seed;
  io::write_hanyang_case(dir / "uwb", simulate_uwb_site(path, site), hanyang_reference(path, kTagHeight));
}

}  // namespace ctxfuse::sim

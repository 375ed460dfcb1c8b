// Each constraint reduces the drift of a simulated GNSS outage (drive_filter.hpp): the RMS over
// seeds of the horizontal error (or the heading error) at the outage's end, with and without.
#include <gtest/gtest.h>

#include <iostream>

#include "drive_filter.hpp"

namespace {
using namespace ctxfuse;
using namespace ctxfuse::test;

constexpr int kSeeds = 8;
const Eigen::Vector3d kGyroBias = Eigen::Vector3d(0.05, -0.04, 0.06) * kDeg;  // [rad/s]
const Eigen::Vector3d kAccelBias(0.02, -0.015, 0.03);                          // [m/s^2]

struct Rms {
  double horizontal = 0.0, heading = 0.0;
};

Rms rms_over_seeds(const Constraints& c, const std::function<double(double)>& speed, double outage_start,
                   double outage_end, double duration) {
  Rms out;
  const Nav15 m = drive_model<Nav15>();
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const Drive d = simulate_drive(
        duration, speed, [&](double t) { return 0.1 * std::sin(2.0 * 3.14159265 * t / 40.0) * speed(t) / 10.0; },
        kGyroBias, kAccelBias, static_cast<std::uint64_t>(seed));
    eskf::Belief<Nav15> b = drive_prior<Nav15>(d);
    const DriveResult r = run_drive(d, m, b, c, outage_start, outage_end, static_cast<std::uint64_t>(seed));
    out.horizontal += r.horizontal_error * r.horizontal_error;
    out.heading += r.heading_error * r.heading_error;
  }
  out.horizontal = std::sqrt(out.horizontal / kSeeds);
  out.heading = std::sqrt(out.heading / kSeeds);
  return out;
}

TEST(GinsConstraints, NonHolonomicConstraintReducesOutageDrift) {
  // Moving throughout; 30 s outage after 60 s of GNSS.
  auto speed = [](double) { return 10.0; };
  const Rms none = rms_over_seeds({}, speed, 60.0, 90.0, 91.0);
  Constraints c;
  c.nhc = true;
  const Rms nhc = rms_over_seeds(c, speed, 60.0, 90.0, 91.0);
  std::cout << "30 s outage, horizontal RMS at its end: none " << none.horizontal << " m, NHC " << nhc.horizontal
            << " m\n";
  // Measured (8 seeds): none 0.533 m, NHC 0.427 m.
  EXPECT_LT(nhc.horizontal, none.horizontal);
}

TEST(GinsConstraints, ZeroVelocityUpdateReducesOutageDriftAcrossAStop) {
  // Outage 60-95 s; the car decelerates from 62 s, stands 67-82 s, drives off at 87 s.
  auto speed = [](double t) { return speed_with_stop(t, 62.0, 15.0); };
  const Rms none = rms_over_seeds({}, speed, 60.0, 95.0, 96.0);
  Constraints z;
  z.zupt = true;
  const Rms zupt = rms_over_seeds(z, speed, 60.0, 95.0, 96.0);
  Constraints zh = z;
  zh.zihr = true;
  const Rms zihr = rms_over_seeds(zh, speed, 60.0, 95.0, 96.0);
  std::cout << "35 s outage with a 15 s stop, horizontal RMS: none " << none.horizontal << " m, ZUPT "
            << zupt.horizontal << " m, ZUPT+ZIHR " << zihr.horizontal << " m; heading RMS none "
            << none.heading / kDeg << " deg, ZUPT " << zupt.heading / kDeg << " deg, ZUPT+ZIHR "
            << zihr.heading / kDeg << " deg\n";
  // Measured (8 seeds): none 0.541 m, ZUPT 0.392 m. ZIHR as a heading hold does not help here:
  // ZUPT+ZIHR 3.74 m, heading 1.47 deg against 0.36 deg with ZUPT alone. The held heading is
  // the filter's own estimate at the stop, and holding it as an absolute measurement (0.1 deg)
  // both freezes that error and claims to know it, which blocks the heading correction the
  // ZUPT gets through the velocity errors of the deceleration. Reported, not asserted.
  EXPECT_LT(zupt.horizontal, none.horizontal);
}

}  // namespace

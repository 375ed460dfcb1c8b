// Soak (issue 18 item 5): a long simulated drive at 100 Hz through the geodetic GNSS/INS
// error-state filter (models/ins_nav.hpp, full mechanisation, GNSS position with a gate) and
// the region pipeline's plain IMM (pipelines/region_imm: Aided<ImmCore<FixedTransition<3>>>,
// default Settings, GNSS fixes, the no-side-slip constraint at the speed samples), checking
// after every step of each:
//   - no NaN: every mean and covariance finite;
//   - every covariance symmetric (largest |P - P'| within 1e-12 of the largest |P|) and
//     Cholesky-positive definite (the INS filter's, each IMM mode's, the IMM's combined one
//     at each receiver epoch);
//   - the horizontal error, largest per bucket of simulated time (an hour by default), with
//     periodic GNSS: fixes at 1 Hz but for a 60 s outage every 10 minutes;
//   - the CPU time per IMU step of each filter (with its checks), per bucket, from the thread
//     CPU clock read once per filter and simulated second: the first bucket against the last
//     says whether the time per step is flat.
// The vehicle drives laps of a circle of 200 m radius (accelerate 10 s to 12 m/s, cruise
// 260 s, brake 10 s, stand 20 s; 300 s a lap), so the truth stays bounded however long the run.
// Both truths are integrated with the filters' own mechanisations from noise-free inputs that
// steer them onto that target (so only the sensors' errors separate truth and filter); the
// sensors add white noise of the densities each filter assumes and random-walk biases.
//
// scripts/soak.sh [hours] runs the program (tests/reliability/soak_main.cpp); the ctest
// reliability_soak_test runs 10 simulated minutes with stated bounds.
#pragma once

#include <time.h>

#include <Eigen/Cholesky>

#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/models/ins_nav.hpp"
#include "ctxfuse/models/ins_updates.hpp"
#include "ctxfuse/pipelines/region_imm/estimators.hpp"
#include "ctxfuse/pipelines/region_imm/run.hpp"
#include "ctxfuse/sim/random.hpp"

namespace ctxfuse::reliability::soak {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kDeg = kPi / 180.0;

struct Config {
  double seconds = 600.0;         // simulated duration
  double bucket_s = 3600.0;       // time per step and largest error reported per bucket
  std::uint64_t seed = 1;
  double outage_period_s = 600.0;  // a GNSS outage of outage_s at the middle of every period
  double outage_s = 60.0;
  double gnss_sigma = 0.5;         // [m] per axis, both filters
};

// The bounds asserted on the largest horizontal error [m], at the fixes 30 s or more after an
// outage and anywhere (the outages' ends included), and on the share of epochs whose error
// exceeds the chi-square(2) 99.9 % quantile of the filter's own covariance (0.1 % expected;
// a covariance half what it should be puts 3.2 % there). The error bounds are set about 1.2-1.4
// times what seed 1 measured (docs/reliability.md): regression bounds, not physics.
struct Bounds {
  double ins_gnss, ins_any, imm_gnss, imm_any;
  double max_share_above_999 = 0.01;
};
// 10 simulated minutes (reliability_soak_test): measured 0.81, 33.10, 1.01, 8.84 m (g++ and clang alike).
inline constexpr Bounds kTenMinutes{1.0, 40.0, 1.2, 12.0};
// Up to 24 simulated hours (the program): measured over 24 h 1.10, 35.55, 1.67, 19.66 m.
inline constexpr Bounds kDay{1.5, 50.0, 2.5, 30.0};

/// What one filter did over the run.
struct FilterReport {
  std::size_t steps = 0, updates = 0, gated = 0, refused = 0;  // refused: predictions or updates not accepted
  std::size_t non_finite = 0, asymmetric = 0, not_pd = 0;      // checks failed
  double worst_asymmetry = 0.0;      // largest |P - P'| / max |P| seen
  double max_error_gnss = 0.0;       // [m] largest horizontal error at fixes 30 s or more after an outage
  double max_error = 0.0;            // [m] largest horizontal error anywhere (outages included)
  // The horizontal error against the filter's own horizontal covariance, e' P^-1 e
  // (chi-square(2) for a consistent filter): the largest, and the share of the checked epochs
  // above the 99.9 % quantile (13.82).
  double max_position_nees = 0.0;
  std::size_t nees_checked = 0, nees_above_999 = 0;
  std::vector<double> bucket_ns_per_step, bucket_max_error;
  bool clean() const { return refused == 0 && non_finite == 0 && asymmetric == 0 && not_pd == 0; }
  double share_above_999() const {
    return nees_checked ? static_cast<double>(nees_above_999) / static_cast<double>(nees_checked) : 0.0;
  }
  bool within(double bound_gnss, double bound_any, double max_share) const {
    return max_error_gnss <= bound_gnss && max_error <= bound_any && share_above_999() <= max_share;
  }
};

struct Report {
  FilterReport ins, imm;
  double seconds = 0.0;
  bool passed(const Bounds& b) const {
    return ins.clean() && imm.clean() && ins.within(b.ins_gnss, b.ins_any, b.max_share_above_999) &&
           imm.within(b.imm_gnss, b.imm_any, b.max_share_above_999);
  }
};

/// The vehicle's target: speed along a circle of radius 200 m; heading (ENU, from east,
/// anticlockwise) the tangent's.
struct Track {
  static constexpr double lap = 300.0, v = 12.0, radius = 200.0;
  static double speed(double t) {
    const double u = std::fmod(t, lap);
    if (u < 10.0) return v * u / 10.0;
    if (u < 270.0) return v;
    if (u < 280.0) return v * (280.0 - u) / 10.0;
    return 0.0;
  }
  /// Distance driven since the start.
  static double distance(double t) {
    const double per_lap = 0.5 * v * 10.0 + v * 260.0 + 0.5 * v * 10.0;
    const double laps = std::floor(t / lap), u = t - laps * lap;
    double d = laps * per_lap;
    if (u < 10.0) return d + 0.5 * v * u * u / 10.0;
    d += 0.5 * v * 10.0;
    if (u < 270.0) return d + v * (u - 10.0);
    d += v * 260.0;
    if (u < 280.0) return d + v * (u - 270.0) - 0.5 * v * (u - 270.0) * (u - 270.0) / 10.0;
    return d + 0.5 * v * 10.0;
  }
  static double heading_enu(double t) { return distance(t) / radius; }
};

inline bool in_outage(const Config& c, double t) {
  const double u = std::fmod(t, c.outage_period_s), start = 0.5 * c.outage_period_s;
  return u >= start && u < start + c.outage_s;
}
inline bool settled(const Config& c, double t) {  // 30 s or more after the last outage's end
  const double u = std::fmod(t, c.outage_period_s), end = 0.5 * c.outage_period_s + c.outage_s;
  return t >= 30.0 && !(u >= 0.5 * c.outage_period_s && u < end + 30.0);
}

inline double thread_cpu_ns() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e9 * static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec);
}

/// The checks of the header on one covariance (and whether the mean is finite).
template <int N>
void check(FilterReport& r, bool mean_finite, const SquareMatrix<N>& P) {
  if (!mean_finite || !P.allFinite()) {
    ++r.non_finite;
    return;
  }
  const double scale = P.cwiseAbs().maxCoeff();
  const double asym = (P - P.transpose()).cwiseAbs().maxCoeff() / (scale > 0.0 ? scale : 1.0);
  r.worst_asymmetry = std::max(r.worst_asymmetry, asym);
  if (asym > 1e-12) ++r.asymmetric;
  if (Eigen::LLT<SquareMatrix<N>>(P).info() != Eigen::Success) ++r.not_pd;
}

/// The horizontal error e at time t, an epoch of bucket b, with the filter's covariance P of it.
inline void note(FilterReport& r, const Config& c, std::size_t b, double t, const Eigen::Vector2d& e,
                 const Eigen::Matrix2d& P, bool at_fix) {
  const double error = e.norm();
  const double nees = e.dot(P.ldlt().solve(e));
  r.max_position_nees = std::max(r.max_position_nees, nees);
  ++r.nees_checked;
  r.nees_above_999 += nees > 13.815510557964274 ? 1 : 0;  // chi-square(2) 99.9 %: -2 ln(0.001)
  r.max_error = std::max(r.max_error, error);
  if (at_fix && settled(c, t)) r.max_error_gnss = std::max(r.max_error_gnss, error);
  if (r.bucket_max_error.size() <= b) r.bucket_max_error.resize(b + 1, 0.0);
  r.bucket_max_error[b] = std::max(r.bucket_max_error[b], error);
}

}  // namespace ctxfuse::reliability::soak

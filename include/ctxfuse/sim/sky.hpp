// A deterministic satellite sky: three Walker-like MEO constellations on circular orbits
// (GPS-, Galileo- and BeiDou-MEO-like), a spherical earth, and the receiver's look angles.
// Realistic enough for visibility, C/N0 and DOP studies: ~28 satellites above 5 deg, moving
// a few degrees over a ten-minute drive.
#pragma once

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

namespace ctxfuse::sim {

struct LookAngle {
  int sat_id = 0;             // 100*system + number: 1xx GPS-like, 2xx Galileo-like, 3xx BeiDou-like
  double elevation_deg = 0.0;
  double azimuth_deg = 0.0;   // clockwise from north, [0, 360)
  Eigen::Vector3d los_enu = Eigen::Vector3d::Zero();  // unit vector receiver -> satellite
};

struct Constellation {
  int system = 1;
  int planes = 6;
  int per_plane = 4;
  double radius_m = 26'560e3;
  double inclination_deg = 55.0;
  double period_s = 43'082.0;
  double phase_offset_deg = 0.0;  // Walker phasing between adjacent planes
};

inline std::array<Constellation, 3> default_constellations() {
  return {Constellation{1, 6, 4, 26'560e3, 55.0, 43'082.0, 15.0}, Constellation{2, 3, 8, 29'600e3, 56.0, 50'680.0, 15.0},
          Constellation{3, 3, 8, 27'906e3, 55.0, 46'404.0, 15.0}};
}

class Sky {
 public:
  Sky(double latitude_deg, double longitude_deg, double start_s)
      : start_s_(start_s), constellations_(default_constellations()) {
    const double d2r = std::numbers::pi / 180.0;
    const double lat = latitude_deg * d2r, lon = longitude_deg * d2r;
    receiver_ = kEarthRadius * Eigen::Vector3d(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat));
    east_ = Eigen::Vector3d(-std::sin(lon), std::cos(lon), 0.0);
    north_ = Eigen::Vector3d(-std::sin(lat) * std::cos(lon), -std::sin(lat) * std::sin(lon), std::cos(lat));
    up_ = receiver_.normalized();
  }

  /// Look angles of every satellite above `mask_deg` at drive time t (s). The receiver's
  /// own displacement (hundreds of metres) is negligible against orbit radii and ignored.
  std::vector<LookAngle> visible(double t, double mask_deg) const {
    std::vector<LookAngle> out;
    visible(t, mask_deg, out);
    return out;
  }
  void visible(double t, double mask_deg, std::vector<LookAngle>& out) const {
    out.clear();
    const double d2r = std::numbers::pi / 180.0;
    const double time = start_s_ + t;
    const double earth_angle = kEarthRate * time;
    for (const auto& c : constellations_) {
      const double n = 2.0 * std::numbers::pi / c.period_s;
      const double inc = c.inclination_deg * d2r;
      for (int p = 0; p < c.planes; ++p) {
        const double raan = 2.0 * std::numbers::pi * p / c.planes - earth_angle;
        for (int k = 0; k < c.per_plane; ++k) {
          const double u = 2.0 * std::numbers::pi * k / c.per_plane + p * c.phase_offset_deg * d2r + n * time;
          // Orbit plane -> inclined -> rotated by the node's longitude in the earth-fixed frame.
          const double xo = c.radius_m * std::cos(u), yo = c.radius_m * std::sin(u);
          const double xi = xo, yi = yo * std::cos(inc), zi = yo * std::sin(inc);
          const Eigen::Vector3d sat(xi * std::cos(raan) - yi * std::sin(raan), xi * std::sin(raan) + yi * std::cos(raan), zi);
          const Eigen::Vector3d los = (sat - receiver_).normalized();
          const double e = los.dot(east_), nn = los.dot(north_), up = los.dot(up_);
          const double el = std::asin(std::clamp(up, -1.0, 1.0)) / d2r;
          if (el < mask_deg) continue;
          double az = std::atan2(e, nn) / d2r;
          if (az < 0.0) az += 360.0;
          out.push_back({c.system * 100 + p * c.per_plane + k + 1, el, az, Eigen::Vector3d(e, nn, up)});
        }
      }
    }
  }

 private:
  static constexpr double kEarthRadius = 6'371e3;
  static constexpr double kEarthRate = 7.2921151467e-5;  // rad/s
  double start_s_;
  std::array<Constellation, 3> constellations_;
  Eigen::Vector3d receiver_, east_, north_, up_;
};

/// Dilution of precision of a set of line-of-sight unit vectors (ENU) for a position + one
/// clock solution. Returns false (and leaves the outputs untouched) with fewer than 4
/// satellites or a singular geometry.
inline bool dilution_of_precision(const std::vector<Eigen::Vector3d>& los_enu, double& pdop, double& hdop, double& vdop) {
  if (los_enu.size() < 4) return false;
  Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
  for (const auto& u : los_enu) {
    const Eigen::Vector4d row(-u.x(), -u.y(), -u.z(), 1.0);
    normal += row * row.transpose();
  }
  const Eigen::Matrix4d q = normal.inverse();
  if (!q.allFinite() || q(0, 0) <= 0.0 || q(1, 1) <= 0.0 || q(2, 2) <= 0.0) return false;
  hdop = std::sqrt(q(0, 0) + q(1, 1));
  vdop = std::sqrt(q(2, 2));
  pdop = std::sqrt(q(0, 0) + q(1, 1) + q(2, 2));
  return pdop < 1e3;
}

}  // namespace ctxfuse::sim

// WGS-84 ellipsoid: radii of curvature, normal gravity, earth rate and transport rate in the
// local north/east/down frame, and the geodetic position block (latitude, longitude, height
// with its error in metres north/east/down) used by the geodetic INS (models/ins_nav.hpp).
#pragma once

#include <cmath>

#include "ctxfuse/core/block_sparsity.hpp"
#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse::earth {

inline constexpr double kSemiMajor = 6378137.0;                     // a [m]
inline constexpr double kFlattening = 1.0 / 298.257223563;          // f
inline constexpr double kEccentricity2 = kFlattening * (2.0 - kFlattening);
inline constexpr double kRate = 7.292115e-5;                        // [rad/s]
inline constexpr double kGravityEquator = 9.7803253359;             // [m/s^2]
inline constexpr double kSomiglianaK = 0.00193185265241;
inline constexpr double kGravityM = 0.00344978650684;               // omega^2 a^2 b / GM

/// Meridian (north-south) and prime-vertical (east-west) radii of curvature [m].
struct Radii {
  double meridian;
  double prime_vertical;
};
inline Radii radii(double lat) {
  const double s = std::sin(lat);
  const double w2 = 1.0 - kEccentricity2 * s * s;
  const double w = std::sqrt(w2);
  return {kSemiMajor * (1.0 - kEccentricity2) / (w2 * w), kSemiMajor / w};
}

/// Normal gravity (Somigliana, second-order height term) [m/s^2], positive down: gravitation
/// plus the centrifugal term, so an accelerometer at rest on the earth reads its negative.
inline double normal_gravity(double lat, double h) {
  const double s2 = std::sin(lat) * std::sin(lat);
  const double g0 = kGravityEquator * (1.0 + kSomiglianaK * s2) / std::sqrt(1.0 - kEccentricity2 * s2);
  return g0 * (1.0 - 2.0 / kSemiMajor * (1.0 + kFlattening + kGravityM - 2.0 * kFlattening * s2) * h +
               3.0 * h * h / (kSemiMajor * kSemiMajor));
}

/// Earth rotation in the north/east/down frame at latitude lat.
inline Eigen::Vector3d earth_rate_ned(double lat) { return {kRate * std::cos(lat), 0.0, -kRate * std::sin(lat)}; }

/// Rotation of the north/east/down frame with respect to the earth as it moves with v_ned.
inline Eigen::Vector3d transport_rate_ned(double lat, double h, const Eigen::Vector3d& v) {
  const Radii r = radii(lat);
  return {v(1) / (r.prime_vertical + h), -v(0) / (r.meridian + h), -v(1) * std::tan(lat) / (r.prime_vertical + h)};
}

/// Metres north/east/down per (rad latitude, rad longitude, m height): d(NED)/d(llh).
inline Eigen::Vector3d ned_per_llh(double lat, double h) {
  const Radii r = radii(lat);
  return {r.meridian + h, (r.prime_vertical + h) * std::cos(lat), -1.0};
}

/// Geodetic position (latitude [rad], longitude [rad], height [m]) whose error is in metres
/// north/east/down, scaled with the radii at the nominal position:
///   x [+] e = x + diag(1/(M+h), 1/((N+h) cos lat), -1) e.
/// The difference uses the radii of its second argument, so (x [+] e) [-] x = e exactly.
/// After a correction dx the radii change, so an error e about x is
/// diag((M'+h')/(M+h), (N'+h') cos lat' / ((N+h) cos lat), 1) e about x' = x [+] dx.
struct GeodeticRetraction {
  static constexpr int dim = 3;
  static constexpr BlockKind reset_kind = BlockKind::diagonal;
  using Value = Eigen::Vector3d;
  static Value identity() { return Value::Zero(); }
  static Value inject(const Value& x, const Vector<3>& e) { return x + e.cwiseQuotient(ned_per_llh(x(0), x(2))); }
  static Vector<3> difference(const Value& a, const Value& b) {
    Vector<3> d = a - b;
    d(1) = std::remainder(d(1), 2.0 * 3.14159265358979323846);  // across the antimeridian
    return d.cwiseProduct(ned_per_llh(b(0), b(2)));
  }
  static SquareMatrix<3> reset_jacobian(const Value& x, const Vector<3>& dx) {
    const Value x_new = inject(x, dx);
    return ned_per_llh(x_new(0), x_new(2)).cwiseQuotient(ned_per_llh(x(0), x(2))).asDiagonal();
  }
  static bool is_finite(const Value& x) { return all_finite(x); }
};

}  // namespace ctxfuse::earth

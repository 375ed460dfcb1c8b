// GNSS position noise policies: a small type the GNSS/INS filter holds as a template argument
// and asks for the fix's R. Both policies share one interface:
//
//   Status observe(const SceneProbabilities& p);    // the scene classifier's output at a fix
//   double sigma() const;                           // [m], the same on each axis
//   Eigen::Matrix3d ned_covariance() const;         // sigma^2 I [m^2], north/east/down
//   Eigen::Matrix3d geodetic(const Eigen::Vector3d& llh) const;  // R for (lat, lon, h)
//
// SceneAdaptiveGnssNoise is the scene paper's eq. 20-21 (digest section B):
//   sigma = P0 E0 + P1 E1 + P2 E2              (E = 2, 10, 100 m: open, obstructed, indoor)
//   R     = diag((sigma / (M + h))^2, (sigma / ((N + h) cos lat))^2, sigma^2)
// for latitude and longitude in radians and height in metres. The paper writes one earth
// radius R_e for both; here the meridian radius M and the prime-vertical radius N of WGS-84
// at the fix (earth::radii), so R is in exactly the units of models::GnssGeodeticPosition,
// whose Jacobian uses the same radii. FixedGnssNoise returns one configured sigma.
//
// Probabilities are checked before use: every P_i finite and >= 0, and |sum P_i - 1| <= the
// stated tolerance (default 1e-6; libsvm's pairwise coupling sums to one within ~1e-15, and a
// caller that rounds its probabilities can widen it). A refused observation returns a Status
// (invalid input: measurement_noise_non_finite for a NaN or Inf, measurement_out_of_domain for
// a negative one or a sum off one) and leaves sigma, and hence R, as it was. The fixed policy
// checks the same way, so swapping policies does not change what counts as bad input.
// Neither allocates; both are plain values.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cmath>

#include "ctxfuse/core/status.hpp"
#include "ctxfuse/models/earth.hpp"

namespace ctxfuse::policies {

inline constexpr int kSceneClasses = 3;  // open, obstructed, indoor (sim::Scene order)
using SceneProbabilities = std::array<double, kSceneClasses>;

/// The check both policies apply (see the header comment).
inline Status check_scene_probabilities(const SceneProbabilities& p, double tolerance) {
  double total = 0.0;
  for (double v : p) {
    if (!std::isfinite(v)) return Status::invalid(Problem::measurement_noise_non_finite);
    if (v < 0.0) return Status::invalid(Problem::measurement_out_of_domain);
    total += v;
  }
  if (!(std::abs(total - 1.0) <= tolerance)) return Status::invalid(Problem::measurement_out_of_domain);
  return Status{};
}

/// R of a geodetic fix (lat, lon [rad], h [m]) with the same sigma [m] on each NED axis.
inline Eigen::Matrix3d geodetic_isotropic_noise(double sigma, const Eigen::Vector3d& llh) {
  const Eigen::Vector3d per = earth::ned_per_llh(llh(0), llh(2));  // m per (rad, rad, m)
  return (Eigen::Vector3d::Constant(sigma).cwiseQuotient(per)).cwiseAbs2().asDiagonal();
}

/// Shared accessors of both policies over their current sigma.
template <class Derived>
struct IsotropicGnssNoise {
  Eigen::Matrix3d ned_covariance() const {
    const double s = static_cast<const Derived&>(*this).sigma();
    return Eigen::Matrix3d::Identity() * s * s;
  }
  Eigen::Matrix3d geodetic(const Eigen::Vector3d& llh) const {
    return geodetic_isotropic_noise(static_cast<const Derived&>(*this).sigma(), llh);
  }
};

/// The scene paper's eq. 20-21.
class SceneAdaptiveGnssNoise : public IsotropicGnssNoise<SceneAdaptiveGnssNoise> {
 public:
  /// scene_sigma: E_i [m] per scene; each must be finite and > 0, the tolerance finite and
  /// >= 0 (else the defaults are kept and valid() is false). Before the first accepted
  /// observation sigma is E_0 (open sky).
  explicit SceneAdaptiveGnssNoise(const std::array<double, kSceneClasses>& scene_sigma = {2.0, 10.0, 100.0},
                                  double tolerance = 1e-6)
      : tolerance_(tolerance) {
    bool ok = std::isfinite(tolerance) && tolerance >= 0.0;
    for (double e : scene_sigma) ok = ok && std::isfinite(e) && e > 0.0;
    if (ok) scene_sigma_ = scene_sigma; else tolerance_ = 1e-6;
    valid_ = ok;
    sigma_ = scene_sigma_[0];
  }

  bool valid() const { return valid_; }
  const std::array<double, kSceneClasses>& scene_sigma() const { return scene_sigma_; }
  double tolerance() const { return tolerance_; }

  Status observe(const SceneProbabilities& p) {
    const Status s = check_scene_probabilities(p, tolerance_);
    if (!s.accepted()) return s;
    double sigma = 0.0;
    for (int i = 0; i < kSceneClasses; ++i) sigma += p[static_cast<std::size_t>(i)] * scene_sigma_[static_cast<std::size_t>(i)];
    sigma_ = sigma;
    return s;
  }
  double sigma() const { return sigma_; }

 private:
  std::array<double, kSceneClasses> scene_sigma_{2.0, 10.0, 100.0};
  double tolerance_ = 1e-6;
  double sigma_ = 2.0;
  bool valid_ = true;
};

/// One sigma whatever the scene: the non-adaptive baseline with the same interface.
class FixedGnssNoise : public IsotropicGnssNoise<FixedGnssNoise> {
 public:
  explicit FixedGnssNoise(double sigma = 2.0, double tolerance = 1e-6) : sigma_(sigma), tolerance_(tolerance) {}
  bool valid() const { return std::isfinite(sigma_) && sigma_ > 0.0; }
  Status observe(const SceneProbabilities& p) const { return check_scene_probabilities(p, tolerance_); }
  double sigma() const { return sigma_; }

 private:
  double sigma_;
  double tolerance_;
};

}  // namespace ctxfuse::policies

// Snapshot multilateration: the horizontal position of a tag at a known height from the ranges
// of one time stamp to anchors at known positions, by Gauss-Newton, with its covariance
// sigma^2 (J'J)^-1 and a status. It starts UWB-only trackers, re-anchors filters after an
// integrity fault (policies/integrity.hpp), and is the least-squares baseline of UWB papers.
//
// A snapshot is refused, never guessed: fewer than three anchors (two leave the mirror image
// about their line as good a fit), anchors (nearly) collinear with the tag, no convergence in
// `max_iterations`, or an RMS residual above `max_rms_m` (an NLOS range among them: with four or
// more anchors the residual test can see one). Ranges or anchors that are not finite are
// invalid input.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

#include "ctxfuse/core/status.hpp"
#include "ctxfuse/messages/sensors.hpp"

namespace ctxfuse {

struct MultilaterationOptions {
  double tag_height_m = 1.0;  // tag z in the anchors' frame
  double sigma_m = 0.15;      // 1-sigma of one range (scales the covariance)
  double max_rms_m = 0.45;    // residual test; infinity turns it off
  int max_iterations = 20;
  double min_information = 1e-3;  // det(J'J) below it: degenerate geometry
  // Where Gauss-Newton starts; not finite: near the anchors' centroid. With anchors spread
  // over a few metres and the tag far away the cost has a mirror-image minimum, so a caller
  // that must not land in it solves from several starts and keeps the best fit.
  Eigen::Vector2d initial = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
};

/// A snapshot solution in D = 2 (horizontal, tag at a known height) or D = 3 unknowns.
template <int D>
struct MultilaterationOf {
  Status status = Status::invalid(Problem::too_few_measurements);
  Eigen::Matrix<double, D, 1> position = Eigen::Matrix<double, D, 1>::Zero();
  Eigen::Matrix<double, D, D> cov = Eigen::Matrix<double, D, D>::Zero();
  double rms_m = 0.0;  // RMS range residual at the solution
  int iterations = 0;
  bool ok() const { return status.accepted(); }
};
using Multilateration = MultilaterationOf<2>;
using Multilateration3d = MultilaterationOf<3>;

namespace detail {
/// Gauss-Newton on the ranges from `p` (D = 2: z held at o.tag_height_m), with the checks of
/// the header comment. The one solver behind multilaterate and multilaterate_3d.
template <int D>
MultilaterationOf<D> solve_ranges(std::span<const messages::UwbRange> ranges, Eigen::Matrix<double, D, 1> p,
                                  const MultilaterationOptions& o) {
  using V = Eigen::Matrix<double, D, 1>;
  using M = Eigen::Matrix<double, D, D>;
  MultilaterationOf<D> out;
  M JtJ;
  double rms = 0.0;
  for (int iter = 0;; ++iter) {
    JtJ.setZero();
    V Jtr = V::Zero();
    double sq = 0.0;
    for (const auto& r : ranges) {
      const double z = D == 3 ? p(D - 1) : o.tag_height_m;
      const Eigen::Vector3d d(p(0) - r.anchor_position.x(), p(1) - r.anchor_position.y(), z - r.anchor_position.z());
      const double n = d.norm();
      if (!(n > 1e-6)) {
        out.status = Status::failure(Problem::degenerate_geometry);
        return out;
      }
      const V j = d.head<D>() / n;
      const double res = r.range_m - n;
      JtJ += j * j.transpose();
      Jtr += j * res;
      sq += res * res;
    }
    rms = std::sqrt(sq / static_cast<double>(ranges.size()));
    out.iterations = iter + 1;
    // A near-singular J'J: anchors (nearly) collinear (coplanar in 3-D) with the tag, the
    // mirror ambiguity open.
    if (JtJ.determinant() < o.min_information) {
      out.status = Status::failure(Problem::degenerate_geometry);
      return out;
    }
    const V step = JtJ.ldlt().solve(Jtr);
    p += step;
    if (step.norm() < 1e-6) break;
    if (iter + 1 >= o.max_iterations) {
      out.status = Status::failure(Problem::not_converged);
      return out;
    }
  }
  out.position = p;
  out.rms_m = rms;
  if (!p.allFinite()) {
    out.status = Status::failure(Problem::non_finite_state);
    return out;
  }
  if (rms > o.max_rms_m) {
    out.status = Status{Outcome::gated, Problem::residual_above_threshold};
    return out;
  }
  out.cov = o.sigma_m * o.sigma_m * JtJ.inverse();
  out.status = Status{};
  return out;
}

inline Status check_ranges(std::span<const messages::UwbRange> ranges, std::size_t needed) {
  if (ranges.size() < needed) return Status::invalid(Problem::too_few_measurements);
  for (const auto& r : ranges)
    if (!std::isfinite(r.range_m) || !r.anchor_position.allFinite()) return Status::invalid(Problem::non_finite_measurement);
  return Status{};
}

/// Where Gauss-Newton starts horizontally: o.initial, else off the anchors' centroid a little
/// (on an anchor the Jacobian row vanishes).
inline Eigen::Vector2d initial_xy(std::span<const messages::UwbRange> ranges, const MultilaterationOptions& o) {
  if (o.initial.allFinite()) return o.initial;
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const auto& r : ranges) c += r.anchor_position.head<2>();
  return c / static_cast<double>(ranges.size()) + Eigen::Vector2d(0.37, 0.23);
}
}  // namespace detail

// multilaterate and multilaterate_3d are templates of a defaulted parameter (called as plain
// functions) so that a source that includes this header and calls neither compiles no solver.

/// The position that best fits `ranges` (all of one time stamp, one per anchor).
template <class = void>
Multilateration multilaterate(std::span<const messages::UwbRange> ranges, const MultilaterationOptions& o = {}) {
  Multilateration out;
  if (const Status st = detail::check_ranges(ranges, 3); !st.accepted()) {
    out.status = st;
    return out;
  }
  return detail::solve_ranges<2>(ranges, detail::initial_xy(ranges, o), o);
}

/// The 3-D position (x, y, z) that best fits `ranges` to four or more anchors that are not
/// coplanar (o.tag_height_m unused; o.initial's x, y as in multilaterate). The cost has a
/// minimum on each side of the anchors' mean height when they are nearly coplanar, so it
/// solves from 1 m above and below their highest and lowest anchors and keeps the best fit.
template <class = void>
Multilateration3d multilaterate_3d(std::span<const messages::UwbRange> ranges, const MultilaterationOptions& o = {}) {
  Multilateration3d best;
  if (const Status st = detail::check_ranges(ranges, 4); !st.accepted()) {
    best.status = st;
    return best;
  }
  const Eigen::Vector2d xy = detail::initial_xy(ranges, o);
  double lo = ranges.front().anchor_position.z(), hi = lo;
  for (const auto& r : ranges) {
    lo = std::min(lo, r.anchor_position.z());
    hi = std::max(hi, r.anchor_position.z());
  }
  best = detail::solve_ranges<3>(ranges, Eigen::Vector3d(xy.x(), xy.y(), hi + 1.0), o);
  const auto below = detail::solve_ranges<3>(ranges, Eigen::Vector3d(xy.x(), xy.y(), lo - 1.0), o);
  if (below.ok() && (!best.ok() || below.rms_m < best.rms_m)) best = below;
  return best;
}

}  // namespace ctxfuse

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

#include <cmath>
#include <limits>
#include <span>

#include "ctxfuse/core/status.hpp"
#include "ctxfuse/io/messages.hpp"

namespace ctxfuse::filters {

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

struct Multilateration {
  Status status = Status::invalid(Problem::too_few_measurements);
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  double rms_m = 0.0;  // RMS range residual at the solution
  int iterations = 0;
  bool ok() const { return status.accepted(); }
};

/// The position that best fits `ranges` (all of one time stamp, one per anchor).
inline Multilateration multilaterate(std::span<const io::UwbRange> ranges, const MultilaterationOptions& o = {}) {
  Multilateration out;
  if (ranges.size() < 3) return out;
  for (const auto& r : ranges)
    if (!std::isfinite(r.range_m) || !r.anchor_position.allFinite()) {
      out.status = Status::invalid(Problem::non_finite_measurement);
      return out;
    }
  Eigen::Vector2d p = o.initial;
  if (!p.allFinite()) {
    p.setZero();
    for (const auto& r : ranges) p += r.anchor_position.head<2>();
    p /= static_cast<double>(ranges.size());
    // Off the centroid a little: on an anchor the Jacobian row vanishes.
    p += Eigen::Vector2d(0.37, 0.23);
  }
  Eigen::Matrix2d JtJ;
  double rms = 0.0;
  for (int iter = 0;; ++iter) {
    JtJ.setZero();
    Eigen::Vector2d Jtr = Eigen::Vector2d::Zero();
    double sq = 0.0;
    for (const auto& r : ranges) {
      const Eigen::Vector3d d(p.x() - r.anchor_position.x(), p.y() - r.anchor_position.y(), o.tag_height_m - r.anchor_position.z());
      const double n = d.norm();
      if (!(n > 1e-6)) {
        out.status = Status::failure(Problem::degenerate_geometry);
        return out;
      }
      const Eigen::Vector2d j = d.head<2>() / n;
      const double res = r.range_m - n;
      JtJ += j * j.transpose();
      Jtr += j * res;
      sq += res * res;
    }
    rms = std::sqrt(sq / static_cast<double>(ranges.size()));
    out.iterations = iter + 1;
    // A near-singular J'J: anchors (nearly) collinear with the tag, the mirror ambiguity open.
    if (JtJ.determinant() < o.min_information) {
      out.status = Status::failure(Problem::degenerate_geometry);
      return out;
    }
    const Eigen::Vector2d step = JtJ.ldlt().solve(Jtr);
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

}  // namespace ctxfuse::filters

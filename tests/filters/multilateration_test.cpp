// Snapshot multilateration (filters/multilateration.hpp) against hand geometry, with the
// status of every refusal.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <vector>

#include "ctxfuse/filters/multilateration.hpp"

namespace {
using namespace ctxfuse;

std::vector<messages::UwbRange> exact_ranges(const Eigen::Vector3d& tag, std::span<const Eigen::Vector3d> anchors) {
  std::vector<messages::UwbRange> out;
  for (std::size_t a = 0; a < anchors.size(); ++a) {
    messages::UwbRange r;
    r.anchor_id = static_cast<int>(a);
    r.anchor_position = anchors[a];
    r.range_m = (tag - anchors[a]).norm();
    out.push_back(r);
  }
  return out;
}

const std::array<Eigen::Vector3d, 4> kAnchors{Eigen::Vector3d(0, 0, 3), Eigen::Vector3d(10, 0, 3), Eigen::Vector3d(10, 8, 3),
                                              Eigen::Vector3d(0, 8, 3)};

TEST(Multilateration, ExactRangesGiveThePointAndTheTextbookCovariance) {
  // Tag at (4, 3), height 1; anchors at height 3.
  const Eigen::Vector2d truth(4.0, 3.0);
  const MultilaterationOptions o{.tag_height_m = 1.0, .sigma_m = 0.1, .max_rms_m = 0.3};
  const auto ranges = exact_ranges(Eigen::Vector3d(4.0, 3.0, 1.0), kAnchors);
  const auto snap = multilaterate(ranges, o);
  ASSERT_TRUE(snap.ok()) << describe(snap.status.problem);
  EXPECT_LT((snap.position - truth).norm(), 1e-9);
  EXPECT_LT(snap.rms_m, 1e-9);
  // sigma^2 (J'J)^-1 with the unit horizontal directions J written out by hand.
  Eigen::Matrix2d JtJ = Eigen::Matrix2d::Zero();
  for (const auto& a : kAnchors) {
    const Eigen::Vector2d d(truth.x() - a.x(), truth.y() - a.y());
    const double n = std::sqrt(d.squaredNorm() + (1.0 - a.z()) * (1.0 - a.z()));
    JtJ += (d / n) * (d / n).transpose();
  }
  EXPECT_LT((snap.cov - 0.01 * JtJ.inverse()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Multilateration, RefusalsSayWhy) {
  const MultilaterationOptions o{.tag_height_m = 1.0, .sigma_m = 0.1, .max_rms_m = 0.3};
  const auto ranges = exact_ranges(Eigen::Vector3d(4.0, 3.0, 1.0), kAnchors);
  // Two anchors: the mirror image is as good a fit.
  auto two = multilaterate(std::span(ranges).first(2), o);
  EXPECT_EQ(two.status.outcome, Outcome::invalid_input);
  EXPECT_EQ(two.status.problem, Problem::too_few_measurements);
  // A 2 m NLOS excess on one of four ranges: residuals far above line-of-sight noise.
  auto nlos = ranges;
  nlos[1].range_m += 2.0;
  const auto gated = multilaterate(nlos, o);
  EXPECT_EQ(gated.status.outcome, Outcome::gated);
  EXPECT_EQ(gated.status.problem, Problem::residual_above_threshold);
  EXPECT_GT(gated.rms_m, 0.3);
  // Without the residual test the same ranges give a (biased) fix.
  auto loose = o;
  loose.max_rms_m = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(multilaterate(nlos, loose).ok());
  // Three collinear anchors with the tag on their line: no horizontal fix across it.
  const std::array<Eigen::Vector3d, 3> line{Eigen::Vector3d(0, 0, 3), Eigen::Vector3d(5, 0, 3), Eigen::Vector3d(10, 0, 3)};
  const auto on_line = multilaterate(exact_ranges(Eigen::Vector3d(4.0, 0.0, 1.0), line), o);
  EXPECT_EQ(on_line.status.outcome, Outcome::numerical_failure);
  EXPECT_EQ(on_line.status.problem, Problem::degenerate_geometry);
  // A non-finite range is invalid input.
  auto bad = ranges;
  bad[2].range_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(multilaterate(bad, o).status.problem, Problem::non_finite_measurement);
  // One iteration is not enough to converge from the centroid.
  auto once = o;
  once.max_iterations = 1;
  EXPECT_EQ(multilaterate(ranges, once).status.problem, Problem::not_converged);
}

// 3-D: exact ranges to five anchors at two heights give the point (from below and from above
// the anchors) and the textbook covariance sigma^2 (J'J)^-1 with 3-D unit directions; four
// coplanar anchors and the tag in their plane leave z unobservable (degenerate); three ranges
// are too few.
TEST(Multilateration, ThreeDimensionalFitAndItsRefusals) {
  const std::array<Eigen::Vector3d, 5> anchors{Eigen::Vector3d(0, 0, 0.5), Eigen::Vector3d(10, 0, 3), Eigen::Vector3d(10, 8, 0.5),
                                               Eigen::Vector3d(0, 8, 3), Eigen::Vector3d(5, 9, 4)};
  const MultilaterationOptions o{.sigma_m = 0.1};
  for (const Eigen::Vector3d truth : {Eigen::Vector3d(4, 3, 1.3), Eigen::Vector3d(7, 2, -0.4), Eigen::Vector3d(3, 6, 5.0)}) {
    const auto snap = multilaterate_3d(exact_ranges(truth, anchors), o);
    ASSERT_TRUE(snap.ok()) << describe(snap.status.problem);
    EXPECT_LT((snap.position - truth).norm(), 1e-9) << truth.transpose();
    Eigen::Matrix3d JtJ = Eigen::Matrix3d::Zero();
    for (const auto& a : anchors) {
      const Eigen::Vector3d u = (truth - a).normalized();
      JtJ += u * u.transpose();
    }
    EXPECT_LT((snap.cov - 0.01 * JtJ.inverse()).norm(), 1e-9 * snap.cov.norm());
  }
  // All anchors at 3 m and the tag at 3 m: every direction horizontal, no vertical information.
  const auto flat = multilaterate_3d(exact_ranges(Eigen::Vector3d(4, 3, 3), kAnchors), o);
  EXPECT_EQ(flat.status.problem, Problem::degenerate_geometry);
  const auto three = multilaterate_3d(exact_ranges(Eigen::Vector3d(4, 3, 1), std::span(kAnchors).first(3)), o);
  EXPECT_EQ(three.status.problem, Problem::too_few_measurements);
}

}  // namespace

// The 20-state filter (Ins15 augmented with mounting pitch/heading and lever arm) equals the
// 15-state one when the extra blocks are held at zero with zero covariance and zero noise:
// same drive, same GNSS and NHC updates, same gate.
#include <gtest/gtest.h>

#include "drive_filter.hpp"

namespace {
using namespace ctxfuse;
using namespace ctxfuse::test;

TEST(GinsAugmented, TwentyStatesWithFrozenExtraBlocksEqualFifteen) {
  const Drive d = simulate_drive(
      40.0, [](double) { return 10.0; }, [](double t) { return 0.1 * std::sin(2.0 * 3.14159265 * t / 40.0); },
      Eigen::Vector3d(0.02, -0.02, 0.03) * kDeg, Eigen::Vector3d(0.01, -0.01, 0.02), 3);
  const Nav15 m15 = drive_model<Nav15>();
  const Nav20 m20 = drive_model<Nav20>();  // extra blocks: constants (tau infinite, no noise)
  eskf::Belief<Nav15> b15 = drive_prior<Nav15>(d);
  eskf::Belief<Nav20> b20 = drive_prior<Nav20>(d);
  Constraints c;
  c.nhc = true;
  const DriveResult r15 = run_drive(d, m15, b15, c, 25.0, 35.0, 3);
  const DriveResult r20 = run_drive(d, m20, b20, c, 25.0, 35.0, 3);
  EXPECT_EQ(r15.gated, r20.gated);
  const Vector<15> diff = m15.difference(Nav20::base_part(b20.nominal), b15.nominal);
  EXPECT_LT(diff.head<3>().norm(), 1e-8);  // [m]; roundoff of latitude in radians is ~1e-9 m
  EXPECT_LT(diff.tail<12>().cwiseAbs().maxCoeff(), 1e-10);
  const SquareMatrix<15> P20 = b20.cov.topLeftCorner<15, 15>();
  EXPECT_LT(((P20 - b15.cov).cwiseAbs().array() / (b15.cov.diagonal() * b15.cov.diagonal().transpose()).cwiseSqrt().array())
                .maxCoeff(),
            1e-8);
  // The frozen blocks stayed exactly where they were.
  EXPECT_EQ(b20.nominal.get<"lever">().norm(), 0.0);
  EXPECT_EQ((b20.cov.bottomRows<5>().cwiseAbs().maxCoeff()), 0.0);
  // And the run was not trivial: the filter moved 400 m and dead-reckoned 10 s.
  EXPECT_GT(r15.horizontal_error, 0.0);
}

}  // namespace

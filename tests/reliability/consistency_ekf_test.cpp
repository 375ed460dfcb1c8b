// Monte Carlo consistency of the EKF on a nonlinear problem whose noise is exactly what the
// filter assumes: a planar constant-velocity target (white acceleration noise, the model's own
// discrete Q) ranged by three anchors (white range noise of the model's sigma). 100 seeded
// runs; the check of consistency_report.hpp must accept the matched filter and reject the same
// filter with its process noise halved (Q/2 in the filter, Q in the truth).
// The linear case (position fixes, the process noise under-stated 20x) is in
// tests/eval/consistency_test.cpp; this one uses the range model's Jacobian and Q/2.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <array>

#include "consistency_report.hpp"
#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/models/kinematic.hpp"

// Named, not anonymous: the area's sources share one unity build (tests/CMakeLists.txt).
namespace consistency_ekf {
using namespace ctxfuse;
using L = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;
using Cv = models::ConstantVelocity<L, 2>;
using Range = models::RangeToPoint<L, 2>;

constexpr int runs = 100, epochs = 200;
constexpr double dt = 0.1, accel_psd = 1.0, range_sigma = 0.1;

reliability::Verdict monte_carlo(double filter_psd_factor) {
  Cv truth;
  truth.accel_psd = accel_psd;
  Cv assumed = truth;
  assumed.accel_psd *= filter_psd_factor;
  std::array<Range, 3> ranges;
  const Vector<2> anchors[3] = {{-30.0, 0.0}, {30.0, 0.0}, {0.0, 40.0}};
  for (int i = 0; i < 3; ++i) {
    ranges[i].anchor = anchors[i];
    ranges[i].sigma = range_sigma;
  }
  const SquareMatrix<4> Q_chol = Eigen::LLT<SquareMatrix<4>>(truth.noise(Vector<4>::Zero(), {}, dt)).matrixL();
  const Vector<4> prior_sd(0.5, 0.5, 0.3, 0.3);

  eval::MonteCarloAverage nees(epochs), nis(epochs);
  for (int r = 0; r < runs; ++r) {
    sim::Rng rng(20261201u + static_cast<std::uint64_t>(r));
    auto normal4 = [&] { return rng.normals<4>(); };
    const auto start = test::draw_start(Vector<4>(0.0, 5.0, 1.0, 0.5), prior_sd, rng);
    Vector<4> x = start.truth;
    Ekf<Cv> f(assumed, start.prior);
    for (int k = 0; k < epochs; ++k) {
      x = truth.predict(x, {}, dt, nullptr) + Q_chol * normal4();
      EXPECT_TRUE(f.predict({}, dt).accepted());
      // Sequential scalar updates: for a linear model their innovations are independent, so
      // the sum of the three NIS is chi-square(3); here it is so to first order.
      double nis_sum = 0.0;
      for (const Range& h : ranges) {
        const double z = (L::get<"p">(x) - h.anchor).norm() + range_sigma * rng.normal();
        const Status s = f.update(h, Vector<1>(z));
        EXPECT_TRUE(s.accepted());
        nis_sum += s.nis;
      }
      nis.add(static_cast<std::size_t>(k), nis_sum);
      nees.add(static_cast<std::size_t>(k), eval::nees<4>(x - f.belief().mean, f.belief().cov));
    }
  }
  return {eval::check_bands(nees, 4, runs), eval::check_bands(nis, 3, runs)};
}

TEST(EkfConsistency, MatchedNoiseIsConsistent) {
  const auto v = monte_carlo(1.0);
  reliability::print_verdict("ekf_cv_ranges", v);
  EXPECT_TRUE(v.consistent());
}

TEST(EkfConsistency, HalvedProcessNoiseIsRejected) {
  const auto v = monte_carlo(0.5);
  reliability::print_verdict("ekf_cv_ranges_half_q", v);
  EXPECT_FALSE(v.consistent());
}

}  // namespace consistency_ekf

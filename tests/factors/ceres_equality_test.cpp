// Ceres as the independent reference: its automatic Jacobians of every factor (through the
// templated residuals, so through the models' value<T>) equal the analytic ones to 1e-9, and
// the smoother's windows, solved by Ceres, give the smoother's solution to 1e-6.
#include <gtest/gtest.h>

#include "ceres_factors.hpp"
#include "ctxfuse/filters/factors.hpp"
#include "ctxfuse/filters/fixed_lag.hpp"
#include "ctxfuse/models/averaged_range.hpp"
#include "ctxfuse/models/linear.hpp"
#include "straight_turn.hpp"

namespace {
using namespace ctxfuse;
using test::autodiff_cost;
using PV3 = Layout<StateBlock<"p", 3>, StateBlock<"v", 3>>;

Vector<6> sample_state(int k) {
  Vector<6> x;
  x << 1.0 + k, -2.0 + 0.5 * k, 0.3 * k, 2.0 - k, 0.7, -0.4 * k;
  return x;
}

/// Ceres' Jacobians (row-major) of a unary factor at x against evaluate()'s analytic ones.
template <UnaryFactor F>
double unary_gap(const F& f, const Vector<F::slot_dims[0]>& x) {
  constexpr int m = F::dim, n = F::slot_dims[0];
  std::unique_ptr<ceres::CostFunction> cost(autodiff_cost(f));
  Vector<m> r;
  Eigen::Matrix<double, m, n, (n == 1 ? Eigen::ColMajor : Eigen::RowMajor)> J;
  const double* params[] = {x.data()};
  double* jac[] = {J.data()};
  EXPECT_TRUE(cost->Evaluate(params, r.data(), jac));
  Matrix<m, n> analytic;
  const Vector<m> r_analytic = f.evaluate(x, &analytic);
  EXPECT_LT((r - r_analytic).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT(analytic.norm(), 0.1);  // a factor that sees its slot
  return (Matrix<m, n>(J) - analytic).cwiseAbs().maxCoeff();
}

template <BinaryFactor F>
double binary_gap(const F& f, const Vector<F::slot_dims[0]>& a, const Vector<F::slot_dims[1]>& b) {
  constexpr int m = F::dim, n = F::slot_dims[0];
  std::unique_ptr<ceres::CostFunction> cost(autodiff_cost(f));
  Vector<m> r;
  Eigen::Matrix<double, m, n, Eigen::RowMajor> Ja, Jb;
  const double* params[] = {a.data(), b.data()};
  double* jac[] = {Ja.data(), Jb.data()};
  EXPECT_TRUE(cost->Evaluate(params, r.data(), jac));
  Matrix<m, n> Aa, Ab;
  EXPECT_LT((r - f.evaluate(a, b, &Aa, &Ab)).cwiseAbs().maxCoeff(), 1e-12);
  return std::max((Matrix<m, n>(Ja) - Aa).cwiseAbs().maxCoeff(), (Matrix<m, n>(Jb) - Ab).cwiseAbs().maxCoeff());
}

TEST(CeresEquality, AutoDiffJacobiansEqualAnalyticOnes) {
  for (int k = 0; k < 4; ++k) {
    models::RangeToPoint<PV3, 3> range;
    range.anchor = {5.0, -3.0, 2.5};
    range.sigma = 0.15;
    MeasurementFactor<6, models::RangeToPoint<PV3, 3>> rf;
    ASSERT_TRUE(make_measurement_factor<6>(range, Vector<1>(4.0), sample_state(k), rf));
    EXPECT_LT(unary_gap(rf, sample_state(k)), 1e-9) << "range " << k;

    models::LinearMeasurement<2, 6> lm;
    lm.H << 1, 0.5, 0, 0, -1, 0, 0, 0, 2, 0.3, 0, 1;
    lm.R << 0.5, 0.1, 0.1, 0.2;
    MeasurementFactor<6, models::LinearMeasurement<2, 6>> lf;
    ASSERT_TRUE(make_measurement_factor<6>(lm, Vector<2>(0.4, -1.0), sample_state(k), lf));
    EXPECT_LT(unary_gap(lf, sample_state(k)), 1e-9) << "linear " << k;

    models::BlockObservation<PV3, "v"> obs;
    MeasurementFactor<6, models::BlockObservation<PV3, "v">> of;
    ASSERT_TRUE(make_measurement_factor<6>(obs, Vector<3>(1, 2, 3), sample_state(k), of));
    EXPECT_LT(unary_gap(of, sample_state(k)), 1e-9) << "observation " << k;

    Gaussian<6> g;
    g.mean = sample_state(k + 1);
    g.cov.diagonal() << 1, 2, 3, 0.5, 0.25, 4;
    g.cov(0, 3) = g.cov(3, 0) = 0.2;
    PriorFactor<6> pf;
    ASSERT_TRUE(make_prior_factor(g, pf));
    EXPECT_LT(unary_gap(pf, sample_state(k)), 1e-9) << "prior " << k;

    models::ConstantVelocity<PV3, 3> cv;
    cv.accel_psd = 0.7;
    MotionFactor<models::ConstantVelocity<PV3, 3>> cf;
    ASSERT_TRUE(make_motion_factor(cv, NoInput{}, 0.1 + 0.2 * k, sample_state(k), cf));
    EXPECT_LT(binary_gap(cf, sample_state(k), sample_state(k + 1)), 1e-9) << "constant velocity " << k;

    models::LinearProcess<6, 2> lp;
    lp.F = SquareMatrix<6>::Identity() + 0.1 * SquareMatrix<6>::Ones();
    lp.B.setConstant(0.5);
    lp.Q = SquareMatrix<6>::Identity() * (0.1 + k);
    MotionFactor<models::LinearProcess<6, 2>> lpf;
    ASSERT_TRUE(make_motion_factor(lp, Vector<2>(0.3, -0.2), 0.1, sample_state(k), lpf));
    EXPECT_LT(binary_gap(lpf, sample_state(k), sample_state(k + 1)), 1e-9) << "linear process " << k;

    using PVB = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>, StateBlock<"b", 3>>;
    models::AveragedRangeWithBias<PVB> avg;
    avg.anchor = {2.5, -0.87, 1.97};
    avg.tag_height = 1.0;
    avg.samples = 3;
    avg.period_s = 0.1;
    avg.bias_slot = k % 3;
    Vector<7> xb;
    xb << sample_state(k).head<4>(), 0.05, -0.02, 0.1 * k;
    MeasurementFactor<7, models::AveragedRangeWithBias<PVB>> avf;
    ASSERT_TRUE(make_measurement_factor<7>(avg, Vector<1>(6.0), xb, avf));
    EXPECT_LT(unary_gap(avf, xb), 1e-9) << "averaged range with bias " << k;

    models::AccelerationDriven<PV3, 3> imu;
    imu.accel_psd = 0.05;
    MotionFactor<models::AccelerationDriven<PV3, 3>> af;
    ASSERT_TRUE(make_motion_factor(imu, Vector<3>(0.3 * k, -1.0, 0.2), 0.01 + 0.05 * k, sample_state(k), af));
    EXPECT_LT(binary_gap(af, sample_state(k), sample_state(k + 1)), 1e-9) << "acceleration driven " << k;
  }
}

TEST(CeresEquality, CeresSolvesTheSmoothersWindowsToTheSameSolution) {
  using namespace test;
  const StraightTurnDrive drive(11, 30.0);
  constexpr int K = 10;
  using Smoother = FixedLagSmoother<Cv2, Range2, K, 4>;
  Smoother smoother(drive.motion());
  Gaussian<4> g;
  g.mean = drive.epochs[0].truth + Vector<4>(0.5, -0.5, 0.3, -0.3);
  ASSERT_TRUE(smoother.initialise(0.0, g));
  int compared = 0;
  for (std::size_t k = 1; k < drive.epochs.size(); ++k) {
    Smoother::Measurements m;
    for (int a = 0; a < 4; ++a)  // one anchor left out every third epoch: slots as a mask
      m.add(drive.range(a), Vector<1>(drive.epochs[k].ranges[static_cast<std::size_t>(a)]), (k + a) % 3 != 0);
    ASSERT_TRUE(smoother.step(drive.epochs[k].t, {}, m));
    // Windows early (not yet full, the initial prior) and late (after marginalisations,
    // through the turn, which starts at 20 s).
    if (k != 5 && k != 40 && k != 230 && k != 260) continue;
    const Smoother::Window& w = smoother.window();
    std::array<Vector<4>, K> xs;
    for (int i = 0; i < w.size; ++i)  // start Ceres away from the smoother's answer
      xs[static_cast<std::size_t>(i)] = w.epochs[static_cast<std::size_t>(i)].x + Vector<4>(0.4, -0.3, 0.2, 0.1);
    ceres::Problem problem;
    add_window(w, xs, problem);
    ceres::Solver::Summary summary;
    ceres::Solve(tight_options(), &problem, &summary);
    ASSERT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
    double gap = 0.0;
    for (int i = 0; i < w.size; ++i)
      gap = std::max(gap, (xs[static_cast<std::size_t>(i)] - w.epochs[static_cast<std::size_t>(i)].x).cwiseAbs().maxCoeff());
    std::printf("epoch %d: %d states, largest |x_ceres - x_smoother| %.2e, costs %.10g / %.10g\n", static_cast<int>(k),
                w.size, gap, summary.final_cost, smoother.report().final_cost);
    EXPECT_LT(gap, 1e-6) << "epoch " << k << ": " << summary.BriefReport();
    EXPECT_NEAR(summary.final_cost, smoother.report().final_cost, 1e-9 * summary.final_cost);
    ++compared;
  }
  EXPECT_EQ(compared, 4);
}

}  // namespace

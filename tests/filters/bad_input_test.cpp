// Every rejection names its problem and leaves the belief bit-for-bit unchanged.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>

#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/models/ins.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/models/linear.hpp"

namespace {
using namespace ctxfuse;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

using L = Layout<Block<"p", 2>, Block<"v", 2>>;
using Cv = models::ConstantVelocity<L, 2>;

// Bit-for-bit equality of the values (so that -0.0 vs 0.0 or a changed NaN payload counts).
// Dense Eigen objects only: a struct's padding bytes are not part of its value, and structs
// such as InsState have padding once AVX aligns their quaternion to 32 bytes (x86-64-v3).
template <class Derived>
bool same_bytes(const Eigen::DenseBase<Derived>& a, const Eigen::DenseBase<Derived>& b) {
  return std::memcmp(a.derived().data(), b.derived().data(), sizeof(typename Derived::Scalar) * static_cast<std::size_t>(a.size())) == 0;
}
template <int N>
bool same_bytes(const Gaussian<N>& a, const Gaussian<N>& b) {
  return same_bytes(a.mean, b.mean) && same_bytes(a.cov, b.cov);
}
bool same_bytes(const models::InsState& a, const models::InsState& b) {
  return same_bytes(a.p, b.p) && same_bytes(a.v, b.v) && same_bytes(a.q.coeffs(), b.q.coeffs()) &&
         same_bytes(a.bg, b.bg) && same_bytes(a.ba, b.ba);
}

Gaussian<4> prior() {
  Gaussian<4> b{Vector<4>(1.0, 2.0, 0.5, -0.25), SquareMatrix<4>::Identity()};
  b.cov(0, 2) = b.cov(2, 0) = 0.1;
  return b;
}

void expect_rejected_unchanged(Status s, Outcome outcome, Problem problem, const Gaussian<4>& before,
                               const Gaussian<4>& after) {
  EXPECT_EQ(s.outcome, outcome) << describe(s.outcome);
  EXPECT_EQ(s.problem, problem) << describe(s.problem);
  EXPECT_FALSE(s.accepted());
  EXPECT_TRUE(same_bytes(before, after));
}

TEST(BadInput, EkfPredictRejectsBadTimeSteps) {
  const Cv cv;
  const FilterOptions opts{.max_dt = 1.0};
  for (auto [dt, problem] : {std::pair{0.0, Problem::non_positive_dt}, std::pair{-0.1, Problem::non_positive_dt},
                             std::pair{kNaN, Problem::non_finite_dt}, std::pair{kInf, Problem::non_finite_dt},
                             std::pair{1.5, Problem::dt_above_maximum}}) {
    Gaussian<4> b = prior();
    const Gaussian<4> before = b;
    expect_rejected_unchanged(ekf::predict(cv, b, {}, dt, opts), Outcome::invalid_input, problem, before, b);
  }
}

TEST(BadInput, EkfPredictRejectsBadProcessNoise) {
  Cv cv;
  cv.accel_psd = kNaN;
  Gaussian<4> b = prior();
  const Gaussian<4> before = b;
  expect_rejected_unchanged(ekf::predict(cv, b, {}, 0.1), Outcome::invalid_input, Problem::process_noise_non_finite,
                            before, b);
  cv.accel_psd = -1.0;
  expect_rejected_unchanged(ekf::predict(cv, b, {}, 0.1), Outcome::invalid_input,
                            Problem::process_noise_negative_variance, before, b);
}

TEST(BadInput, EkfPredictRejectsBadInputs) {
  models::LinearProcess<4, 2> lp;
  Gaussian<4> b = prior();
  const Gaussian<4> before = b;
  expect_rejected_unchanged(ekf::predict(lp, b, Vector<2>(kNaN, 0.0), 0.1), Outcome::invalid_input,
                            Problem::non_finite_input, before, b);
  expect_rejected_unchanged(ekf::predict(lp, b, Vector<2>(0.0, 1e300), 0.1), Outcome::invalid_input,
                            Problem::input_magnitude, before, b);
}

TEST(BadInput, EkfUpdateRejectsBadMeasurementsAndNoise) {
  models::BlockObservation<L, "p"> pos;
  const Gaussian<4> before = prior();
  Gaussian<4> b = before;
  expect_rejected_unchanged(ekf::update<4>(pos, b, Vector<2>(kNaN, 0.0)), Outcome::invalid_input,
                            Problem::non_finite_measurement, before, b);
  expect_rejected_unchanged(ekf::update<4>(pos, b, Vector<2>(0.0, -kInf)), Outcome::invalid_input,
                            Problem::non_finite_measurement, before, b);
  expect_rejected_unchanged(ekf::update<4>(pos, b, Vector<2>(0.0, 1e12)), Outcome::invalid_input,
                            Problem::measurement_magnitude, before, b);
  pos.R(1, 1) = kNaN;
  expect_rejected_unchanged(ekf::update<4>(pos, b, Vector<2>(0.0, 0.0)), Outcome::invalid_input,
                            Problem::measurement_noise_non_finite, before, b);
  pos.R << 1.0, 2.0, 2.0, 1.0;  // symmetric but indefinite
  expect_rejected_unchanged(ekf::update<4>(pos, b, Vector<2>(0.0, 0.0)), Outcome::invalid_input,
                            Problem::measurement_noise_not_positive_definite, before, b);
  pos.R.setZero();
  expect_rejected_unchanged(ekf::update<4>(pos, b, Vector<2>(0.0, 0.0)), Outcome::invalid_input,
                            Problem::measurement_noise_not_positive_definite, before, b);

  models::RangeToPoint<L, 2> range;
  expect_rejected_unchanged(ekf::update<4>(range, b, Vector<1>(-1.0)), Outcome::invalid_input,
                            Problem::measurement_out_of_domain, before, b);
}

TEST(BadInput, NumericalFailuresLeaveTheBeliefUnchanged) {
  models::BlockObservation<L, "p"> pos;
  pos.R = SquareMatrix<2>::Identity() * 1e-3;
  Gaussian<4> b = prior();
  b.cov = -SquareMatrix<4>::Identity();  // a corrupted covariance makes S indefinite
  const Gaussian<4> before = b;
  expect_rejected_unchanged(ekf::update<4>(pos, b, Vector<2>(1.0, 2.0)), Outcome::numerical_failure,
                            Problem::innovation_not_positive_definite, before, b);

  // Finite terms whose sum overflows: a velocity near the largest double, correlated with the
  // position, so that a far (but finite) position fix corrects it past DBL_MAX.
  Gaussian<4> big = prior();
  big.mean(2) = 1.7e308;
  big.cov(0, 2) = big.cov(2, 0) = 1.0;
  big.cov(2, 2) = 2.0;
  models::BlockObservation<L, "p"> tight;
  tight.R = SquareMatrix<2>::Identity() * 1e-6;
  const Gaussian<4> before_big = big;
  const FilterOptions any_magnitude{.max_abs_measurement = std::numeric_limits<double>::max()};
  expect_rejected_unchanged(ekf::update<4>(tight, big, Vector<2>(1e308, 2.0), NoGate{}, any_magnitude),
                            Outcome::numerical_failure, Problem::non_finite_state, before_big, big);
}

TEST(BadInput, NonFinitePriorMeanIsRefusedByBothSteps) {
  models::BlockObservation<L, "p"> pos;
  for (int k : {0, 3}) {  // observed by the position update, and not (a velocity)
    for (double bad : {kNaN, kInf}) {
      Gaussian<4> c = prior();
      c.mean(k) = bad;
      const Gaussian<4> before = c;
      expect_rejected_unchanged(ekf::update<4>(pos, c, Vector<2>(1.0, 2.0)), Outcome::invalid_input,
                                Problem::non_finite_prior, before, c);
      expect_rejected_unchanged(ekf::predict(Cv{}, c, {}, 0.1), Outcome::invalid_input, Problem::non_finite_prior,
                                before, c);
    }
  }
}

struct EskfFixture : ::testing::Test {
  models::Ins15Model model;
  eskf::Belief<models::Ins15Model> belief;
  void SetUp() override {
    belief.nominal.p = {1, 2, 3};
    belief.nominal.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
    belief.cov = SquareMatrix<15>::Identity() * 0.1;
  }
  void expect_unchanged(const eskf::Belief<models::Ins15Model>& before) const {
    EXPECT_TRUE(same_bytes(before.nominal, belief.nominal));
    EXPECT_TRUE(same_bytes(before.cov, belief.cov));
  }
};

TEST_F(EskfFixture, RejectsBadImuAndLeavesStateUnchanged) {
  const auto before = belief;
  models::ImuSample u;
  u.accel = {0, 0, 9.81};
  u.gyro(1) = kNaN;
  Status s = eskf::predict(model, belief, u, 0.01);
  EXPECT_EQ(s.problem, Problem::non_finite_input);
  expect_unchanged(before);
  u.gyro = {0, 0, 100.0};  // 5700 deg/s: not a vehicle
  s = eskf::predict(model, belief, u, 0.01);
  EXPECT_EQ(s.problem, Problem::input_magnitude);
  expect_unchanged(before);
  u.gyro.setZero();
  s = eskf::predict(model, belief, u, -0.01);
  EXPECT_EQ(s.problem, Problem::non_positive_dt);
  expect_unchanged(before);
  ASSERT_TRUE(eskf::predict(model, belief, u, 0.01));
}

TEST_F(EskfFixture, RejectsBadFixesAndLeavesStateUnchanged) {
  const auto before = belief;
  models::GnssPosition<> gnss;
  Status s = eskf::update(model, gnss, belief, Vector<3>(1, kNaN, 3));
  EXPECT_EQ(s.problem, Problem::non_finite_measurement);
  expect_unchanged(before);
  gnss.R(2, 2) = -1.0;
  s = eskf::update(model, gnss, belief, Vector<3>(1, 2, 3));
  EXPECT_EQ(s.problem, Problem::measurement_noise_not_positive_definite);
  expect_unchanged(before);
  gnss.R.setIdentity();
  s = eskf::update(model, gnss, belief, Vector<3>(1e4, 2, 3), ChiSquareGate(0.999));
  EXPECT_EQ(s.outcome, Outcome::gated);
  expect_unchanged(before);
  ASSERT_TRUE(eskf::update(model, gnss, belief, Vector<3>(1.1, 2, 3), ChiSquareGate(0.999)));
}

TEST(BadInput, DescribeNamesEveryProblem) {
  for (int p = 0; p <= static_cast<int>(last_problem); ++p)
    EXPECT_NE(describe(static_cast<Problem>(p)), "unknown") << p;
}

}  // namespace

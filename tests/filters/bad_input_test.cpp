// Every rejection names its problem and leaves the belief bit-for-bit unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/models/ins.hpp"
#include "ctxfuse/models/ins_augment.hpp"
#include "ctxfuse/models/ins_nav.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/models/linear.hpp"

namespace {
using namespace ctxfuse;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

using L = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;
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
  expect_rejected_unchanged(ekf::update<4>(tight, big, Vector<2>(1e308, 2.0), policies::NoGate{}, any_magnitude),
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
  s = eskf::update(model, gnss, belief, Vector<3>(1e4, 2, 3), policies::ChiSquareGate(0.999));
  EXPECT_EQ(s.outcome, Outcome::gated);
  expect_unchanged(before);
  ASSERT_TRUE(eskf::update(model, gnss, belief, Vector<3>(1.1, 2, 3), policies::ChiSquareGate(0.999)));
}

// The covariance prediction is the last step that can fail (after the nominal has been
// propagated): an F P F' that overflows, or a NaN in Q, is refused and nothing is written.
TEST_F(EskfFixture, RefusesANonFiniteCovariancePredictionAndLeavesStateUnchanged) {
  models::ImuSample u;
  u.accel = {0, 0, 9.81};
  belief.cov = SquareMatrix<15>::Identity() * std::numeric_limits<double>::max();
  const auto before = belief;
  Status s = eskf::predict(model, belief, u, 0.01);
  EXPECT_EQ(s.outcome, Outcome::numerical_failure);
  EXPECT_EQ(s.problem, Problem::non_finite_covariance);
  expect_unchanged(before);

  belief.cov = SquareMatrix<15>::Identity() * 0.1;
  const auto before_nan = belief;
  model.gyro_noise_density = kNaN;
  SquareMatrix<15> F_used = SquareMatrix<15>::Constant(7.0);
  s = eskf::predict(model, belief, u, 0.01, {}, &F_used);
  EXPECT_EQ(s.outcome, Outcome::invalid_input);
  EXPECT_EQ(s.problem, Problem::process_noise_non_finite);
  expect_unchanged(before_nan);
  EXPECT_TRUE((F_used.array() == 7.0).all());  // F is handed out only on success
}

// The same for the augmented strapdown (its F and Q are built in place around the base's).
struct AugmentedEskfFixture : ::testing::Test {
  using Nav20 = models::Augmented<models::InsNavModel<models::FullStrapdown>, StateBlock<"mount", 2>, StateBlock<"lever", 3>>;
  Nav20 model;
  eskf::Belief<Nav20> belief;
  models::BodyIncrements u;
  void SetUp() override {
    model.extra[0] = models::GaussMarkov{1e-3, 600.0};
    auto& x = belief.nominal;
    x.get<"p">() = Eigen::Vector3d(0.7, -1.5, 210.0);
    x.get<"v">() = Eigen::Vector3d(8.0, -3.0, 0.2);
    x.get<"theta">() = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, -0.3, 1.0).normalized()));
    x.get<"mount">() = Eigen::Vector2d(-0.05, 0.09);
    x.get<"lever">() = Eigen::Vector3d(-1.2, 0.3, 0.6);
    belief.cov = SquareMatrix<20>::Identity() * 0.1;
    belief.cov(0, 3) = belief.cov(3, 0) = 0.02;
    u.dtheta = Eigen::Vector3d(1e-4, -2e-4, 1e-3);
    u.dv = Eigen::Vector3d(0.03, 0.01, -0.098);
  }
  void expect_unchanged(const eskf::Belief<Nav20>& before) const {
    const auto& a = before.nominal;
    const auto& b = belief.nominal;
    EXPECT_TRUE(same_bytes(a.get<"p">(), b.get<"p">()));
    EXPECT_TRUE(same_bytes(a.get<"v">(), b.get<"v">()));
    EXPECT_TRUE(same_bytes(a.get<"theta">().coeffs(), b.get<"theta">().coeffs()));
    EXPECT_TRUE(same_bytes(a.get<"bg">(), b.get<"bg">()));
    EXPECT_TRUE(same_bytes(a.get<"ba">(), b.get<"ba">()));
    EXPECT_TRUE(same_bytes(a.get<"mount">(), b.get<"mount">()));
    EXPECT_TRUE(same_bytes(a.get<"lever">(), b.get<"lever">()));
    EXPECT_TRUE(same_bytes(before.cov, belief.cov));
  }
};

TEST_F(AugmentedEskfFixture, RejectedPredictionsLeaveTheBeliefUnchanged) {
  const auto before = belief;
  Status s = eskf::predict(model, belief, u, -0.01);
  EXPECT_EQ(s.problem, Problem::non_positive_dt);
  expect_unchanged(before);

  models::BodyIncrements bad = u;
  bad.dv(2) = kInf;
  s = eskf::predict(model, belief, bad, 0.01);
  EXPECT_EQ(s.problem, Problem::non_finite_input);
  expect_unchanged(before);

  Nav20 nan_base = model;
  nan_base.base.accel_noise_density = kNaN;
  s = eskf::predict(nan_base, belief, u, 0.01);
  EXPECT_EQ(s.outcome, Outcome::invalid_input);
  EXPECT_EQ(s.problem, Problem::process_noise_non_finite);
  expect_unchanged(before);

  Nav20 nan_extra = model;
  nan_extra.extra[1].density = kNaN;  // the lever arm's variance (a random walk: density^2 dt)
  s = eskf::predict(nan_extra, belief, u, 0.01);
  EXPECT_EQ(s.problem, Problem::process_noise_non_finite);
  expect_unchanged(before);

  belief.cov = SquareMatrix<20>::Identity() * std::numeric_limits<double>::max();
  const auto before_huge = belief;
  s = eskf::predict(model, belief, u, 0.01);
  EXPECT_EQ(s.outcome, Outcome::numerical_failure);
  EXPECT_EQ(s.problem, Problem::non_finite_covariance);
  expect_unchanged(before_huge);

  belief.cov(19, 4) = belief.cov(4, 19) = kNaN;  // one NaN far from the diagonal
  belief.cov.diagonal().setConstant(0.1);
  const auto before_nan_cov = belief;
  s = eskf::predict(model, belief, u, 0.01);
  EXPECT_EQ(s.outcome, Outcome::numerical_failure);
  EXPECT_EQ(s.problem, Problem::non_finite_covariance);
  expect_unchanged(before_nan_cov);
}

// Every element of P+ finite although their sum is not (near the largest double): accepted, and
// equal to F P F' + Q written out densely.
TEST_F(AugmentedEskfFixture, AcceptsAHugeButFiniteCovariance) {
  belief.cov = SquareMatrix<20>::Identity() * (0.25 * std::numeric_limits<double>::max());
  const SquareMatrix<20> P = belief.cov;
  const auto x0 = belief.nominal;
  SquareMatrix<20> F;
  const Status s = eskf::predict(model, belief, u, 0.01, {}, &F);
  ASSERT_TRUE(s.accepted()) << describe(s.problem);
  ASSERT_TRUE(belief.cov.allFinite());
  EXPECT_TRUE(belief.cov == belief.cov.transpose());
  const SquareMatrix<20> Q = model.noise(x0, u, 0.01);
  const SquareMatrix<20> FP = F * P;
  const SquareMatrix<20> expected = FP * F.transpose() + Q;
  for (int j = 0; j < 20; ++j)
    for (int i = j; i < 20; ++i)
      EXPECT_LE(std::abs(belief.cov(i, j) - expected(i, j)),
                1e-12 * std::sqrt(expected(i, i)) * std::sqrt(expected(j, j)))
          << i << ", " << j;
}

TEST(BadInput, DescribeNamesEveryProblem) {
  for (int p = 0; p <= static_cast<int>(last_problem); ++p)
    EXPECT_NE(describe(static_cast<Problem>(p)), "unknown") << p;
}

}  // namespace

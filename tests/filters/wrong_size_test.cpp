// Arguments whose size is known only at run time (Eigen::VectorXd, Map, dynamic segments) at
// the filters' fixed-size entry points: a wrong size is refused with its own Problem before a
// single element is read, and the belief is left bit-for-bit as it was. The release suite
// builds this with -DNDEBUG (Eigen's own size assert compiled out: without the check the
// filter would read past the end and accept), the sanitized suite under AddressSanitizer (a
// read past a heap vector's end is a report). And score(): what an update would say, with
// nothing changed.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <vector>

#include "ctxfuse/filters/ekf.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/filters/factors.hpp"
#include "ctxfuse/filters/federated.hpp"
#include "ctxfuse/filters/fixed_lag.hpp"
#include "ctxfuse/filters/score.hpp"
#include "ctxfuse/models/ins.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/models/linear.hpp"

namespace {
using namespace ctxfuse;

using L = Layout<StateBlock<"p", 2>, StateBlock<"v", 2>>;
using Cv = models::ConstantVelocity<L, 2>;
using Pos = models::BlockObservation<L, "p">;

template <class Derived>
bool bytes_equal(const Eigen::DenseBase<Derived>& a, const Eigen::DenseBase<Derived>& b) {
  return std::memcmp(a.derived().data(), b.derived().data(),
                     sizeof(typename Derived::Scalar) * static_cast<std::size_t>(a.size())) == 0;
}
bool bytes_equal(const Gaussian<4>& a, const Gaussian<4>& b) { return bytes_equal(a.mean, b.mean) && bytes_equal(a.cov, b.cov); }

Gaussian<4> start_belief() {
  Gaussian<4> b{Vector<4>(1.0, 2.0, 0.5, -0.25), SquareMatrix<4>::Identity()};
  b.cov(0, 2) = b.cov(2, 0) = 0.1;
  return b;
}

void expect_wrong_size(Status s, Problem p) {
  EXPECT_EQ(s.outcome, Outcome::invalid_input);
  EXPECT_EQ(s.problem, p) << describe(s.problem);
}

TEST(WrongSize, EkfUpdateRefusesRunTimeSizedMeasurementsOfTheWrongSize) {
  const Pos pos;
  const Gaussian<4> before = start_belief();
  // Heap vectors (ASan sees a read past their end), a Map over one double, a dynamic segment.
  const Eigen::VectorXd short_z = Eigen::VectorXd::Constant(1, 0.3);
  const Eigen::VectorXd long_z = Eigen::VectorXd::Constant(3, 0.3);
  const Eigen::MatrixXd wide_z = Eigen::MatrixXd::Constant(2, 2, 0.3);
  double one = 0.3;
  const Eigen::Map<const Eigen::VectorXd> map_z(&one, 1);
  const Eigen::VectorXd three = Eigen::VectorXd::Constant(3, 0.3);

  Gaussian<4> b = before;
  expect_wrong_size(ekf::update<4>(pos, b, short_z), Problem::measurement_wrong_size);
  expect_wrong_size(ekf::update<4>(pos, b, long_z), Problem::measurement_wrong_size);
  expect_wrong_size(ekf::update<4>(pos, b, wide_z), Problem::measurement_wrong_size);
  expect_wrong_size(ekf::update<4>(pos, b, map_z), Problem::measurement_wrong_size);
  expect_wrong_size(ekf::update<4>(pos, b, three.segment(0, 1)), Problem::measurement_wrong_size);
  EXPECT_TRUE(bytes_equal(before, b));

  Ekf<Cv, policies::ChiSquareGate> filter(Cv{}, before, {}, policies::ChiSquareGate(0.99));
  expect_wrong_size(filter.update(pos, short_z), Problem::measurement_wrong_size);
  expect_wrong_size(filter.score(pos, short_z), Problem::measurement_wrong_size);
  EXPECT_TRUE(bytes_equal(before, filter.belief()));

  fkf::FederatedFilter<Cv, 2> fed(Cv{}, before, {0.5, 0.5});
  expect_wrong_size(fed.update(1, pos, long_z), Problem::measurement_wrong_size);
  const SquareMatrix<4> local_cov = before.cov / 0.5;
  EXPECT_TRUE(bytes_equal(local_cov, fed.local(1).cov));

  MeasurementFactor<4, Pos> factor{pos, Vector<2>(7.0, 7.0), SquareMatrix<2>::Identity()};
  expect_wrong_size(make_measurement_factor<4>(pos, short_z, before.mean, factor), Problem::measurement_wrong_size);
  EXPECT_EQ(factor.z, Vector<2>(7.0, 7.0));
}

// A smoother epoch's slot has no status to refuse with: a run-time sized value does not compile.
template <class Z>
constexpr bool can_add = requires(EpochMeasurements<Pos, 4>& e, const Pos& p, const Z& z) { e.add(p, z); };
static_assert(!can_add<Eigen::VectorXd>);
static_assert(can_add<Vector<2>>);

// The right size through the run-time sized path is the fixed-size update, to the bit.
TEST(WrongSize, RightSizedRunTimeVectorsUpdateAsTheFixedSizeOnes) {
  const Pos pos;
  const Eigen::VectorXd z_dyn = (Eigen::VectorXd(2) << 1.3, 1.7).finished();
  const std::vector<double> raw{9.0, 1.3, 1.7};
  const Eigen::Map<const Eigen::VectorXd> z_map(raw.data() + 1, 2);
  Gaussian<4> fixed = start_belief(), dynamic = start_belief(), mapped = start_belief();
  ASSERT_TRUE(ekf::update<4>(pos, fixed, Vector<2>(1.3, 1.7)));
  ASSERT_TRUE(ekf::update<4>(pos, dynamic, z_dyn));
  ASSERT_TRUE(ekf::update<4>(pos, mapped, z_map));
  EXPECT_TRUE(bytes_equal(fixed, dynamic));
  EXPECT_TRUE(bytes_equal(fixed, mapped));
}

TEST(WrongSize, PredictionsRefuseRunTimeSizedInputsOfTheWrongSize) {
  const models::LinearProcess<4, 2> lp;
  const Gaussian<4> before = start_belief();
  Gaussian<4> b = before;
  const Eigen::VectorXd short_u = Eigen::VectorXd::Constant(1, 0.1);
  expect_wrong_size(ekf::predict(lp, b, short_u, 0.1), Problem::input_wrong_size);
  EXPECT_TRUE(bytes_equal(before, b));

  Ekf<models::LinearProcess<4, 2>> filter(lp, before);
  filter.set_time(0.0);
  expect_wrong_size(filter.predict(short_u, 0.1), Problem::input_wrong_size);
  expect_wrong_size(filter.predict_to(0.1, short_u), Problem::input_wrong_size);
  EXPECT_TRUE(bytes_equal(before, filter.belief()));
  EXPECT_EQ(filter.time(), 0.0);

  const Eigen::VectorXd u = (Eigen::VectorXd(2) << 0.1, -0.2).finished();
  Gaussian<4> fixed = before;
  ASSERT_TRUE(ekf::predict(lp, fixed, Vector<2>(0.1, -0.2), 0.1));
  ASSERT_TRUE(filter.predict_to(0.1, u));
  EXPECT_TRUE(bytes_equal(fixed, filter.belief()));
  EXPECT_EQ(filter.time(), 0.1);

  MotionFactor<models::LinearProcess<4, 2>> motion{lp, Vector<2>::Zero(), 1.0, SquareMatrix<4>::Identity()};
  expect_wrong_size(make_motion_factor(lp, short_u, 0.1, before.mean, motion), Problem::input_wrong_size);
  EXPECT_EQ(motion.dt, 1.0);
}

TEST(WrongSize, EskfRefusesRunTimeSizedFixesOfTheWrongSize) {
  const models::Ins15Model model;
  eskf::Belief<models::Ins15Model> belief;
  belief.nominal.p = {1, 2, 3};
  belief.cov = SquareMatrix<15>::Identity() * 0.1;
  const auto before = belief;
  const models::GnssPosition<> gnss;
  const Eigen::VectorXd fix2 = Eigen::VectorXd::Constant(2, 1.0);
  expect_wrong_size(eskf::update(model, gnss, belief, fix2), Problem::measurement_wrong_size);
  EXPECT_TRUE(bytes_equal(before.nominal.p, belief.nominal.p));
  EXPECT_TRUE(bytes_equal(before.cov, belief.cov));

  Eskf<models::Ins15Model> filter(model, before);
  expect_wrong_size(filter.update(gnss, fix2), Problem::measurement_wrong_size);
  EXPECT_TRUE(bytes_equal(before.cov, filter.belief().cov));
}

// score() is the update's arithmetic without the update: the same NIS, log-likelihood and gate
// verdict to the last bit, and the belief untouched.
TEST(Score, ReportsWhatTheUpdateWouldAndChangesNothing) {
  const Pos pos;
  const policies::ChiSquareGate gate(0.99);
  for (const Vector<2>& z : {Vector<2>(1.3, 1.7), Vector<2>(9.0, -6.0)}) {
    Ekf<Cv, policies::ChiSquareGate> filter(Cv{}, start_belief(), {}, gate);
    const Gaussian<4> before = filter.belief();
    const Status scored = filter.score(pos, z);
    EXPECT_TRUE(bytes_equal(before, filter.belief()));
    const Status updated = filter.update(pos, z);
    EXPECT_EQ(scored.outcome, updated.outcome);
    EXPECT_EQ(scored.dof, 2);
    EXPECT_EQ(scored.nis, updated.nis);
    EXPECT_EQ(scored.log_likelihood, updated.log_likelihood);
    EXPECT_EQ(scored.gate_threshold, updated.gate_threshold);

    // Against the textbook: y = z - H x, S = H P H' + R, NIS = y' S^-1 y,
    // log N(y; 0, S) = -(NIS + log det(2 pi S)) / 2.
    const Vector<2> y = z - before.mean.head<2>();
    const SquareMatrix<2> S = before.cov.topLeftCorner<2, 2>() + pos.R;
    const double nis = y.dot(S.inverse() * y);
    EXPECT_NEAR(scored.nis, nis, 1e-12 * nis);
    EXPECT_NEAR(scored.log_likelihood, -0.5 * (nis + std::log((2.0 * EIGEN_PI * S).determinant())), 1e-12);
    EXPECT_EQ(scored.outcome, nis <= chi_square_quantile(0.99, 2) ? Outcome::accepted : Outcome::gated);
  }
  // The error-state filter's belief too.
  const models::Ins15Model model;
  eskf::Belief<models::Ins15Model> belief;
  belief.nominal.p = {1, 2, 3};
  belief.cov = SquareMatrix<15>::Identity() * 0.1;
  const models::GnssPosition<> gnss;
  const auto before = belief;
  const Status scored = score(gnss, belief, Vector<3>(1.2, 2.1, 2.9));
  EXPECT_TRUE(bytes_equal(before.cov, belief.cov));
  const Status updated = eskf::update(model, gnss, belief, Vector<3>(1.2, 2.1, 2.9));
  EXPECT_EQ(scored.nis, updated.nis);
  EXPECT_EQ(scored.log_likelihood, updated.log_likelihood);
}

TEST(Score, InvalidMeasurementsAreNamedAsTheUpdateNamesThem) {
  const Pos pos;
  const Gaussian<4> b = start_belief();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(score(pos, b, Vector<2>(nan, 0.0)).problem, Problem::non_finite_measurement);
  Gaussian<4> bad = b;
  bad.mean(3) = nan;  // a component the measurement does not see
  EXPECT_EQ(score(pos, bad, Vector<2>(0.0, 0.0)).problem, Problem::non_finite_prior);
  Gaussian<4> updated = bad;
  EXPECT_EQ(ekf::update<4>(pos, updated, Vector<2>(0.0, 0.0)).problem, Problem::non_finite_prior);
}

}  // namespace

// The Jacobian battery of ctxfuse/testing/jacobians.hpp: it passes on the library's models, on
// the manifold where they have one, with their declared block patterns; and it fails, naming
// the entry, on a model with one wrong Jacobian entry, a wrong reset Jacobian, a declared
// transition pattern that leaves out a non-zero block and a measurement whose declared columns
// leave out one it uses.
#include <gtest/gtest.h>

#include <array>

#include "../gins/states.hpp"
#include "ctxfuse/models/ins.hpp"
#include "ctxfuse/models/kinematic.hpp"
#include "ctxfuse/models/planar.hpp"
#include "ctxfuse/testing/jacobians.hpp"

namespace {
using namespace ctxfuse;
namespace ct = ctxfuse::testing;

models::InsState moving_ins_state() {
  models::InsState x;
  x.p = {100.0, -20.0, 3.0};
  x.v = {8.0, 3.0, 0.1};
  x.q = Eigen::Quaterniond(Eigen::AngleAxisd(1.2, Eigen::Vector3d(0.1, 0.2, 1.0).normalized()));
  x.bg = {0.002, -0.001, 0.003};
  x.ba = {0.05, -0.08, 0.02};
  return x;
}

TEST(JacobianBattery, PassesOnTheKinematicAndPlanarModels) {
  using L = Layout<StateBlock<"p", 3>, StateBlock<"v", 3>, StateBlock<"c", 1>>;
  models::ConstantVelocity<L, 3> cv;
  Vector<7> x;
  x << 1, 2, 3, -1, 0.5, 2, 7;
  const auto r = ct::check_transition(cv, x, {}, 0.3);
  EXPECT_TRUE(r) << r;

  models::PlanarImuModel planar;
  Vector<models::PlanarLayout::size> xp;
  xp << 10.0, -4.0, 3.0, 1.0, 0.7, 0.01, 0.1, -0.2;
  models::PlanarImu u;
  u.yaw_rate = 0.3;
  u.accel = {1.2, -0.4};
  for (double dt : {0.01, 0.2}) {
    const auto rp = ct::check_transition(planar, xp, u, dt);
    EXPECT_TRUE(rp) << rp << " dt " << dt;
  }
  models::PlanarRange range;
  range.anchor = {4.0, -2.0, 3.0};
  const auto rr = ct::check_measurement(range, xp);
  EXPECT_TRUE(rr) << rr;
}

TEST(JacobianBattery, PassesOnTheInsModelsOnTheirManifolds) {
  models::Ins15Model m;
  m.gyro_bias.tau = 300.0;
  m.accel_bias.tau = 500.0;
  const models::InsState x = moving_ins_state();
  models::ImuSample u;
  u.gyro = {0.3, -0.2, 0.8};
  u.accel = {1.5, -0.7, 9.5};
  for (double dt : {0.01, 0.2}) {
    const auto r = ct::check_transition(m, x, u, dt);
    EXPECT_TRUE(r) << r << " dt " << dt;
  }
  Vector<15> dx;
  dx << 0.5, -0.3, 0.2, 0.01, 0.02, -0.03, 0.08, -0.15, 0.3, 1e-3, -2e-3, 5e-4, 0.01, 0.02, -0.01;
  const auto rr = ct::check_reset(m, x, dx);
  EXPECT_TRUE(rr) << rr;
  models::GnssPosition<> gnss;
  gnss.lever_arm = {1.2, -0.4, 0.9};
  const auto rg = ct::check_measurement(gnss, m, x);
  EXPECT_TRUE(rg) << rg;

  // The geodetic INS: latitude and longitude in radians, so a position step of metres (the
  // position part of the retraction is linear) where a 1e-6 m step would see their roundoff.
  const test::Nav15 nav;
  const auto xn = test::sample_nav_state();
  std::array<double, 15> steps{};
  steps.fill(1e-5);
  steps[0] = steps[1] = steps[2] = 1e-2;
  ct::JacobianOptions o;
  o.steps = steps;
  const auto rn = ct::check_reset(nav, xn, dx, o);
  EXPECT_TRUE(rn) << rn;
}

// A model that forwards to another and changes one entry of its Jacobian.
template <class Base>
struct OneEntryOff : Base {
  int row = 0, col = 0;
  double by = 1e-3;
  typename Base::State predict(const typename Base::State& x, const typename Base::Input& u, double dt,
                               SquareMatrix<Base::dim>* F) const {
    auto out = Base::predict(x, u, dt, F);
    if (F) (*F)(row, col) += by;
    return out;
  }
};

TEST(JacobianBattery, NamesTheEntryOfAWrongTransitionJacobian) {
  OneEntryOff<models::Ins15Model> m;
  m.row = 4;
  m.col = 7;
  models::ImuSample u;
  u.gyro = {0.3, -0.2, 0.8};
  u.accel = {1.5, -0.7, 9.5};
  const auto r = ct::check_transition(m, moving_ins_state(), u, 0.1);
  EXPECT_FALSE(r);
  EXPECT_EQ(r.what, "transition");
  EXPECT_EQ(r.row, 4);
  EXPECT_EQ(r.col, 7);
  EXPECT_NEAR(r.analytic - r.numerical, 1e-3, 1e-7);
  // An error at the tolerance's scale is caught too, and one well below it is not.
  m.by = 1e-6;
  EXPECT_FALSE(ct::check_transition(m, moving_ins_state(), u, 0.1));
  m.by = 1e-10;
  EXPECT_TRUE(ct::check_transition(m, moving_ins_state(), u, 0.1));
}

struct WrongReset : models::Ins15Model {
  SquareMatrix<15> reset_jacobian(const State&, const Vector<15>&) const { return SquareMatrix<15>::Identity(); }
};

TEST(JacobianBattery, CatchesAResetJacobianThatIgnoresTheRotation) {
  Vector<15> dx = Vector<15>::Zero();
  dx.segment<3>(6) << 0.08, -0.15, 0.3;
  const auto r = ct::check_reset(WrongReset{}, moving_ins_state(), dx);
  EXPECT_FALSE(r);
  EXPECT_GE(r.row, 6);  // in the rotation block
  EXPECT_LT(r.row, 9);
  EXPECT_GE(r.col, 6);
  EXPECT_LT(r.col, 9);
}

// x = (a, b): a' = a + dt b, b' = b; it declares a and b as identity blocks and forgets (a, b).
struct ForgetsABlock {
  using L = Layout<StateBlock<"a", 1>, StateBlock<"b", 1>>;
  using State = Vector<2>;
  using Input = NoInput;
  static constexpr int dim = 2;
  static constexpr auto transition_blocks = block_pattern<L>({{"a", "a", kIdentity}, {"b", "b", kIdentity}});
  State predict(const State& x, const Input&, double dt, SquareMatrix<2>* F) const {
    if (F) *F << 1.0, dt, 0.0, 1.0;
    return {x(0) + dt * x(1), x(1)};
  }
  SquareMatrix<2> noise(const State&, const Input&, double) const { return SquareMatrix<2>::Identity(); }
};

// h(x) = a + b with only a declared.
struct ForgetsAColumn {
  using L = ForgetsABlock::L;
  static constexpr int dim = 1;
  static constexpr auto jacobian_columns = column_pattern<L>({"a"});
  Vector<1> predict(const Vector<2>& x, Matrix<1, 2>* H) const {
    if (H) *H << 1.0, 1.0;
    return Vector<1>(x(0) + x(1));
  }
  SquareMatrix<1> noise(const Vector<2>&) const { return SquareMatrix<1>::Identity(); }
};

TEST(JacobianBattery, CatchesDeclaredPatternsThatLeaveOutANonZeroBlock) {
  const auto r = ct::check_transition(ForgetsABlock{}, Vector<2>(1.0, 2.0), {}, 0.5);
  EXPECT_FALSE(r);
  EXPECT_EQ(r.what, "transition pattern");
  EXPECT_EQ(r.row, 0);
  EXPECT_EQ(r.col, 1);
  EXPECT_NEAR(r.numerical, 0.5, 1e-9);

  const auto h = ct::check_measurement(ForgetsAColumn{}, Vector<2>(1.0, 2.0));
  EXPECT_FALSE(h);
  EXPECT_EQ(h.what, "measurement pattern");
  EXPECT_EQ(h.col, 1);
}

TEST(JacobianBattery, RefusesStepsOfTheWrongSize) {
  const std::array<double, 3> steps{1e-6, 1e-6, 1e-6};
  ct::JacobianOptions o;
  o.steps = steps;
  const auto r = ct::check_transition(ForgetsABlock{}, Vector<2>(1.0, 2.0), {}, 0.5, o);
  EXPECT_FALSE(r);
  EXPECT_NE(r.problem.find("steps"), std::string::npos);
}

}  // namespace

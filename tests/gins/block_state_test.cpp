// Block states: inject/difference per block, the reset Jacobian against central differences of
// the error reparametrisation, and the augmentation's concatenated block patterns.
#include <gtest/gtest.h>

#include "ctxfuse/core/block_state.hpp"
#include "states.hpp"
#include "ctxfuse/testing/jacobians.hpp"

namespace {
using namespace ctxfuse;
using test::Nav15;
using test::Nav20;

template <class Model>
void expect_reset_jacobian_is_the_derivative(const Model& m, const typename Model::State& x,
                                             const Vector<Model::dim>& dx) {
  constexpr int N = Model::dim;
  // True state t = x [+] e_old = (x [+] dx) [+] e_new: e_new(e_old) = (x [+] e_old) [-] (x [+] dx).
  const auto x_new = m.inject(x, dx);
  auto e_new = [&](const Vector<N>& e_old) -> Vector<N> { return m.difference(m.inject(x, e_old), x_new); };
  EXPECT_LT(e_new(dx).norm(), 1e-9);
  // Position errors of metres change latitude by ~1e-7 rad, where one ulp of latitude is
  // ~7e-10 m: a 1e-5 m step would see roundoff, not the derivative. The position part of the
  // map is linear (fixed radii on either side), so a 1 cm step is exact there.
  SquareMatrix<N> G_num;
  for (int i = 0; i < N; ++i) {
    const double h = i < 3 ? 1e-2 : 1e-5;
    Vector<N> ep = dx, em = dx;
    ep(i) += h;
    em(i) -= h;
    G_num.col(i) = (e_new(ep) - e_new(em)) / (2.0 * h);
  }
  const SquareMatrix<N> G = m.reset_jacobian(x, dx);
  EXPECT_LT((G - G_num).cwiseAbs().maxCoeff(), 1e-7) << G - G_num;
}

TEST(BlockState, InjectThenDifferenceReturnsTheError) {
  const Nav20 m;
  const Nav20::State x = test::sample_nav20_state();
  Vector<20> dx;
  dx << 3.0, -2.0, 1.5, 0.1, -0.2, 0.3, 0.05, -0.1, 0.2, 1e-3, -1e-3, 2e-3, 0.01, -0.02, 0.03, 0.01, -0.02, 0.1, 0.2,
      -0.3;
  // Position to within roundoff of latitude in radians (one ulp ~7e-10 m), the rest exactly.
  const Vector<20> round_trip = m.difference(m.inject(x, dx), x) - dx;
  EXPECT_LT(round_trip.head<3>().cwiseAbs().maxCoeff(), 5e-9);
  EXPECT_LT(round_trip.tail<17>().cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT(m.difference(x, x).norm(), 1e-15);
  // 3 m north is 3 / (M + h) rad of latitude.
  const earth::Radii r = earth::radii(x.get<"p">()(0));
  EXPECT_NEAR(m.inject(x, dx).get<"p">()(0) - x.get<"p">()(0), 3.0 / (r.meridian + 210.0), 1e-15);
  EXPECT_NEAR(m.inject(x, dx).get<"p">()(2) - 210.0, -1.5, 1e-12);  // down is minus height
}

TEST(BlockState, ResetJacobianOfTheGeodeticInsIsTheDerivativeOfTheReparametrisation) {
  Vector<15> dx;
  // Large position corrections so that the radii ratio (1e-5 here) is visible.
  dx << 2000.0, -3000.0, 50.0, 0.01, 0.02, -0.03, 0.08, -0.15, 0.3, 1e-3, -2e-3, 5e-4, 0.01, 0.02, -0.01;
  expect_reset_jacobian_is_the_derivative(Nav15{}, test::sample_nav_state(), dx);
  // The position block is not the identity at that size (the radii change with the position).
  const SquareMatrix<15> G = Nav15{}.reset_jacobian(test::sample_nav_state(), dx);
  EXPECT_GT(std::abs(G(1, 1) - 1.0), 1e-6);
}

TEST(BlockState, ResetJacobianOfTheAugmentedInsIsTheDerivativeOfTheReparametrisation) {
  Vector<20> dx = Vector<20>::LinSpaced(20, -0.3, 0.4);
  dx.head<3>() << 500.0, 800.0, -20.0;
  expect_reset_jacobian_is_the_derivative(Nav20{}, test::sample_nav20_state(), dx);
}

TEST(BlockState, PlanarAngleWrapsAcrossPi) {
  using S = BlockState<Layout<StateBlock<"psi", 1>, StateBlock<"x", 2>>, PlanarAngleRetraction, VectorRetraction<2>>;
  S a, b;
  a.get<"psi">()(0) = 179.0 * test::kDeg;
  b.get<"psi">()(0) = -179.0 * test::kDeg;
  EXPECT_NEAR(block_difference(a, b)(0), -2.0 * test::kDeg, 1e-12);
  Vector<3> d(4.0 * test::kDeg, 1.0, 2.0);
  EXPECT_NEAR(block_inject(a, d).get<"psi">()(0), -177.0 * test::kDeg, 1e-12);
}

// The augmented transition pattern is Ins15's plus one diagonal block per extra block, and the
// reset pattern skips the vector blocks' identities.
static_assert(decltype(Nav20::transition_blocks)::size == decltype(Nav15::transition_blocks)::size + 2);
static_assert(Nav20::transition_blocks.row[decltype(Nav15::transition_blocks)::size] == 5);
static_assert(Nav20::transition_blocks.kind[decltype(Nav15::transition_blocks)::size + 1] == BlockKind::diagonal);
static_assert(Nav20::reset_blocks.kind[0] == BlockKind::diagonal && Nav20::reset_blocks.kind[2] == BlockKind::dense &&
              Nav20::reset_blocks.kind[6] == BlockKind::identity);

TEST(BlockState, AugmentedTransitionIsTheBaseOneWithGaussMarkovExtraBlocks) {
  Nav20 m;
  m.extra[0] = models::GaussMarkov{1e-3, 100.0};  // mounting: first-order Gauss-Markov
  const Nav20::State x = test::sample_nav20_state();
  models::BodyIncrements u;
  u.dtheta = Eigen::Vector3d(0.001, -0.002, 0.01);
  u.dv = Eigen::Vector3d(0.02, 0.01, -0.098);
  const double dt = 0.01;
  SquareMatrix<20> F;
  const Nav20::State y = m.predict(x, u, dt, &F);
  SquareMatrix<15> Fb;
  const models::NavState yb = m.base.predict(Nav20::base_part(x), u, dt, &Fb);
  EXPECT_TRUE(Nav20::base_part(y).get<"p">() == yb.get<"p">());
  EXPECT_EQ((F.topLeftCorner<15, 15>() - Fb).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((F.topRightCorner<15, 5>().cwiseAbs().maxCoeff()), 0.0);
  EXPECT_NEAR(F(15, 15), std::exp(-dt / 100.0), 1e-15);
  EXPECT_EQ(F(17, 17), 1.0);  // the lever arm stays a constant
  EXPECT_NEAR(y.get<"mount">()(1), std::exp(-dt / 100.0) * 0.09, 1e-15);
  const SquareMatrix<20> Q = m.noise(x, u, dt);
  EXPECT_NEAR(Q(16, 16), m.extra[0].variance(dt), 1e-20);
  EXPECT_EQ(Q(18, 18), 0.0);
}

}  // namespace

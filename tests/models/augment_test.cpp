// models::Augmented builds its F and Q in place around the base's when the base can write
// into a block (InsNavModel), and copies the base's own F and Q in otherwise: both ways give
// the same numbers, every entry written.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>

#include "ctxfuse/models/ins_augment.hpp"
#include "ctxfuse/models/ins_nav.hpp"

namespace {
using namespace ctxfuse;

template <class Mechanisation>
using Nav = models::InsNavModel<Mechanisation>;

// The same base with only the pointer predict and the returning noise: Augmented copies.
template <class Mechanisation>
struct CopiedNav : Nav<Mechanisation> {
  using B = Nav<Mechanisation>;
  using typename B::Input;
  using typename B::State;
  typename B::State predict(const State& x, const Input& u, double dt, SquareMatrix<B::dim>* F) const {
    return B::predict(x, u, dt, F);
  }
  SquareMatrix<B::dim> noise(const State& x, const Input& u, double dt) const { return B::noise(x, u, dt); }
};

template <class Base>
using Aug = models::Augmented<Base, StateBlock<"mount", 2>, StateBlock<"lever", 3>>;

template <class Derived>
bool same_bytes(const Eigen::DenseBase<Derived>& a, const Eigen::DenseBase<Derived>& b) {
  return std::memcmp(a.derived().data(), b.derived().data(),
                     sizeof(typename Derived::Scalar) * static_cast<std::size_t>(a.size())) == 0;
}

template <class M>
void configure(M& m) {
  m.base.gyro_noise_density = 2e-4;
  m.base.accel_noise_density = 3e-3;
  m.base.gyro_bias = models::GaussMarkov{1e-5, 300.0};
  m.base.accel_bias = models::GaussMarkov{2e-3, 200.0};
  m.extra[0] = models::GaussMarkov{1e-3, 600.0};  // mount: Gauss-Markov
  m.extra[1] = models::GaussMarkov{2e-3};         // lever: random walk
}

template <class Mechanisation>
void expect_in_place_equals_copied() {
  using InPlace = Aug<Nav<Mechanisation>>;
  using Copied = Aug<CopiedNav<Mechanisation>>;
  static_assert(std::is_same_v<typename InPlace::State, typename Copied::State>);
  InPlace a;
  Copied b;
  configure(a);
  configure(b);
  typename InPlace::State x;
  x.template get<"p">() = Eigen::Vector3d(0.7, -1.5, 210.0);
  x.template get<"v">() = Eigen::Vector3d(8.0, -3.0, 0.2);
  x.template get<"theta">() = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, -0.3, 1.0).normalized()));
  x.template get<"bg">() = Eigen::Vector3d(1e-3, -2e-3, 5e-4);
  x.template get<"ba">() = Eigen::Vector3d(0.01, -0.05, 0.02);
  x.template get<"mount">() = Eigen::Vector2d(-0.05, 0.09);
  x.template get<"lever">() = Eigen::Vector3d(-1.2, 0.3, 0.6);
  models::BodyIncrements u;
  u.dtheta = Eigen::Vector3d(1e-4, -2e-4, 1e-3);
  u.dv = Eigen::Vector3d(0.03, 0.01, -0.098);
  u.prev_dtheta = Eigen::Vector3d(2e-4, -1e-4, 9e-4);
  u.prev_dv = Eigen::Vector3d(0.02, 0.015, -0.097);
  u.has_previous = true;
  const double dt = 0.01;

  // Every entry must be written: start from NaN.
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  SquareMatrix<20> Fa = SquareMatrix<20>::Constant(nan), Fb = SquareMatrix<20>::Constant(nan);
  const auto ya = a.predict(x, u, dt, &Fa);
  const auto yb = b.predict(x, u, dt, &Fb);
  const auto za = a.predict(x, u, dt, nullptr);
  EXPECT_TRUE(Fa.allFinite());
  EXPECT_TRUE(same_bytes(Fa, Fb));
  for (const auto* y : {&yb, &za}) {
    EXPECT_TRUE(same_bytes(ya.template get<"p">(), y->template get<"p">()));
    EXPECT_TRUE(same_bytes(ya.template get<"v">(), y->template get<"v">()));
    EXPECT_TRUE(same_bytes(ya.template get<"theta">().coeffs(), y->template get<"theta">().coeffs()));
    EXPECT_TRUE(same_bytes(ya.template get<"bg">(), y->template get<"bg">()));
    EXPECT_TRUE(same_bytes(ya.template get<"ba">(), y->template get<"ba">()));
    EXPECT_TRUE(same_bytes(ya.template get<"mount">(), y->template get<"mount">()));
    EXPECT_TRUE(same_bytes(ya.template get<"lever">(), y->template get<"lever">()));
  }

  const SquareMatrix<20> Qa = a.noise(x, u, dt), Qb = b.noise(x, u, dt);
  EXPECT_TRUE(Qa.allFinite());
  EXPECT_TRUE(same_bytes(Qa, Qb));

  // The base's F and Q in the corner, the extra blocks' decay and variance on the diagonal,
  // zeros elsewhere.
  SquareMatrix<15> F15;
  (void)a.base.predict(InPlace::base_part(x), u, dt, &F15);
  EXPECT_TRUE(same_bytes(Fa.template topLeftCorner<15, 15>().eval(), F15));
  EXPECT_TRUE(same_bytes(Qa.template topLeftCorner<15, 15>().eval(), a.base.noise(InPlace::base_part(x), u, dt)));
  SquareMatrix<5> extra_F = SquareMatrix<5>::Zero(), extra_Q = SquareMatrix<5>::Zero();
  extra_F.diagonal() << a.extra[0].decay(dt), a.extra[0].decay(dt), 1.0, 1.0, 1.0;
  extra_Q.diagonal() << a.extra[0].variance(dt), a.extra[0].variance(dt), a.extra[1].variance(dt),
      a.extra[1].variance(dt), a.extra[1].variance(dt);
  EXPECT_TRUE(same_bytes(Fa.template bottomRightCorner<5, 5>().eval(), extra_F));
  EXPECT_TRUE(same_bytes(Qa.template bottomRightCorner<5, 5>().eval(), extra_Q));
  EXPECT_TRUE((Fa.template topRightCorner<15, 5>().array() == 0.0).all());
  EXPECT_TRUE((Fa.template bottomLeftCorner<5, 15>().array() == 0.0).all());
  EXPECT_TRUE((Qa.template topRightCorner<15, 5>().array() == 0.0).all());
  EXPECT_TRUE((Qa.template bottomLeftCorner<5, 15>().array() == 0.0).all());
}

TEST(Augmented, InPlaceAndCopiedBaseGiveTheSameFAndQSimplified) { expect_in_place_equals_copied<models::SimplifiedStrapdown>(); }
TEST(Augmented, InPlaceAndCopiedBaseGiveTheSameFAndQFull) { expect_in_place_equals_copied<models::FullStrapdown>(); }

}  // namespace

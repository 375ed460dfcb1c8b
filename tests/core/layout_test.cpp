#include <gtest/gtest.h>

#include "ctxfuse/core/layout.hpp"

namespace {
using namespace ctxfuse;

using Nav = Layout<StateBlock<"p", 3>, StateBlock<"v", 3>, StateBlock<"theta", 3>>;
using Bias = Layout<StateBlock<"bg", 3>, StateBlock<"ba", 3>>;
using Full = Concat<Nav, Bias>;
using Planar = Layout<StateBlock<"v", 3>, StateBlock<"p", 3>>;  // same names, other order

static_assert(Nav::size == 9 && Full::size == 15 && Full::block_count == 5);
static_assert(Full::offset<"p">() == 0 && Full::offset<"theta">() == 6 && Full::offset<"ba">() == 12);
static_assert(Full::size_of<"bg">() == 3);
static_assert(Full::contains("bg") && !Nav::contains("bg"));
static_assert(std::is_same_v<Concat<Nav, Bias>, Layout<StateBlock<"p", 3>, StateBlock<"v", 3>, StateBlock<"theta", 3>,
                                                        StateBlock<"bg", 3>, StateBlock<"ba", 3>>>);

TEST(Layout, ViewsReadAndWriteTheNamedBlock) {
  Full::StateVector x = Full::StateVector::LinSpaced(15, 0.0, 14.0);
  EXPECT_EQ(Full::get<"theta">(x)(0), 6.0);
  Full::get<"ba">(x).setConstant(-1.0);
  EXPECT_EQ(x(11), 11.0);
  EXPECT_EQ(x(12), -1.0);
  EXPECT_EQ(x(14), -1.0);

  Full::CovarianceMatrix P = Full::CovarianceMatrix::Zero();
  Full::cov<"v", "bg">(P).setConstant(2.0);
  EXPECT_EQ(P(3, 9), 2.0);
  EXPECT_EQ(P(5, 11), 2.0);
  EXPECT_EQ(P(9, 3), 0.0);
  EXPECT_EQ(P.sum(), 18.0);
}

TEST(Layout, MapAlignsBlocksByNameWhateverTheOrder) {
  using Map = LayoutMap<Planar, Full>;
  // Planar = {v, p}: its element 0 is v.x (Full 3), its element 3 is p.x (Full 0).
  EXPECT_EQ(Map::index[0], 3);
  EXPECT_EQ(Map::index[3], 0);
  EXPECT_EQ(Map::index[5], 2);

  Full::StateVector x = Full::StateVector::LinSpaced(15, 0.0, 14.0);
  const Vector<6> sub = Map::extract(x);
  EXPECT_EQ(sub(0), 3.0);
  EXPECT_EQ(sub(3), 0.0);

  Full::StateVector y = Full::StateVector::Zero();
  Map::insert(sub, y);
  EXPECT_EQ(y.head<6>(), x.head<6>());
  EXPECT_TRUE(y.tail<9>().isZero());

  Matrix<1, 6> J;
  J << 1, 2, 3, 4, 5, 6;
  const Matrix<1, 15> Jw = Map::widen_columns<1, double>(J);
  EXPECT_EQ(Jw(0, 3), 1.0);  // v.x
  EXPECT_EQ(Jw(0, 0), 4.0);  // p.x
  EXPECT_EQ(Jw.tail<9>().sum(), 0.0);

  Full::CovarianceMatrix P;
  for (int i = 0; i < 15; ++i)
    for (int j = 0; j < 15; ++j) P(i, j) = 100 * i + j;
  const SquareMatrix<6> Ps = Map::extract_cov(P);
  EXPECT_EQ(Ps(0, 3), P(3, 0));
  EXPECT_EQ(Ps(4, 1), P(1, 4));
}

}  // namespace

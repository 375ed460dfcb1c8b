#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <array>
#include <cstdlib>
#include <limits>

#include "ctxfuse/core/block_sparsity.hpp"
#include "ctxfuse/filters/eskf.hpp"
#include "ctxfuse/models/ins.hpp"
#include "ctxfuse/models/kinematic.hpp"

namespace {
using namespace ctxfuse;
using L = models::Ins15Layout;

// Every entry outside the declared blocks must be exactly zero, and identity blocks exactly I:
// a pattern that forgets a block would silently drop terms from the covariance.
template <auto Pat, int N>
void expect_covered(const SquareMatrix<N>& A) {
  using PL = typename decltype(Pat)::layout;
  std::array<std::array<bool, N>, N> declared{};
  for (std::size_t k = 0; k < decltype(Pat)::size; ++k) {
    const auto rb = static_cast<std::size_t>(Pat.row[k]), cb = static_cast<std::size_t>(Pat.col[k]);
    for (int i = 0; i < PL::sizes[rb]; ++i)
      for (int j = 0; j < PL::sizes[cb]; ++j) declared[PL::offsets[rb] + i][PL::offsets[cb] + j] = true;
    if (Pat.kind[k] == BlockKind::identity) {
      EXPECT_TRUE(A.block(PL::offsets[rb], PL::offsets[cb], PL::sizes[rb], PL::sizes[cb]).isIdentity(0.0))
          << PL::names[rb] << "," << PL::names[cb];
    }
    if (Pat.kind[k] == BlockKind::diagonal) {
      SquareMatrix<N> off = A;
      auto blk = off.block(PL::offsets[rb], PL::offsets[cb], PL::sizes[rb], PL::sizes[cb]);
      blk.diagonal().setZero();
      EXPECT_TRUE(blk.isZero(0.0)) << "diagonal block " << PL::names[rb] << "," << PL::names[cb] << " is not diagonal";
    }
  }
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j)
      if (!declared[i][j]) {
        EXPECT_EQ(A(i, j), 0.0) << "undeclared non-zero at " << i << "," << j;
      }
}

template <auto Pat, int M, int N>
void expect_columns_covered(const Matrix<M, N>& H) {
  using PL = typename decltype(Pat)::layout;
  std::array<bool, N> declared{};
  for (std::size_t k = 0; k < decltype(Pat)::size; ++k) {
    const auto b = static_cast<std::size_t>(Pat.block[k]);
    for (int j = 0; j < PL::sizes[b]; ++j) declared[PL::offsets[b] + j] = true;
  }
  for (int j = 0; j < N; ++j)
    if (!declared[j]) {
      EXPECT_EQ(H.col(j).cwiseAbs().sum(), 0.0) << "undeclared column " << j;
    }
}

models::InsState state() {
  models::InsState x;
  x.p = {3, 4, 5};
  x.v = {5, -1, 0.3};
  x.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.9, Eigen::Vector3d(1, 2, 3).normalized()));
  x.bg = {0.01, 0.02, -0.01};
  x.ba = {0.1, 0.2, -0.3};
  return x;
}

// F of the 15-state INS model at state() for a turning, accelerating step of 0.05 s.
SquareMatrix<15> ins_transition(const models::Ins15Model& m) {
  models::ImuSample u;
  u.gyro = {0.2, -0.1, 0.4};
  u.accel = {1, 2, 9};
  SquareMatrix<15> F;
  m.predict(state(), u, 0.05, &F);
  return F;
}

// A random symmetric positive semi-definite 15 x 15 covariance.
SquareMatrix<15> random_covariance() {
  const SquareMatrix<15> A = SquareMatrix<15>::Random();
  return A * A.transpose();
}

TEST(BlockSparsity, InsPatternsCoverTheirJacobians) {
  models::Ins15Model m;
  m.gyro_bias.tau = 100.0;
  const SquareMatrix<15> F = ins_transition(m);
  expect_covered<models::Ins15Model::transition_blocks>(F);
  Vector<15> dx = Vector<15>::LinSpaced(15, -0.1, 0.1);
  expect_covered<models::Ins15Model::reset_blocks>(m.reset_jacobian(state(), dx));
  models::GnssPosition<> g;
  g.lever_arm = {0.4, 0.1, 1.0};
  Matrix<3, 15> H;
  g.predict(state(), &H);
  expect_columns_covered<models::GnssPosition<>::jacobian_columns>(H);
}

TEST(BlockSparsity, KinematicPatternsCoverTheirJacobians) {
  using K = Layout<StateBlock<"v", 2>, StateBlock<"p", 2>, StateBlock<"c", 1>>;
  Vector<5> x;
  x << 1, 2, 3, 4, 5;
  models::RangeToPoint<K, 2> r;
  Matrix<1, 5> Hr;
  r.predict(x, &Hr);
  expect_columns_covered<models::RangeToPoint<K, 2>::jacobian_columns>(Hr);
  models::BlockObservation<K, "p"> o;
  Matrix<2, 5> Ho;
  o.predict(x, &Ho);
  expect_columns_covered<models::BlockObservation<K, "p">::jacobian_columns>(Ho);
}

TEST(BlockSparsity, SparseCongruenceEqualsDense) {
  const SquareMatrix<15> F = ins_transition(models::Ins15Model{});
  const SquareMatrix<15> P = random_covariance();
  const SquareMatrix<15> dense = F * P * F.transpose();
  EXPECT_LT((congruence<models::Ins15Model::transition_blocks>(F, P) - dense).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(BlockSparsity, BlockDiagonalResetEqualsDenseCongruence) {
  models::Ins15Model m;
  Vector<15> dx = Vector<15>::Zero();
  L::get<"theta">(dx) = Eigen::Vector3d(0.3, -0.2, 0.5);
  const SquareMatrix<15> G = m.reset_jacobian(state(), dx);
  const SquareMatrix<15> P = random_covariance();
  const Eigen::MatrixXd dense = Eigen::MatrixXd(G) * Eigen::MatrixXd(P) * Eigen::MatrixXd(G).transpose();
  static_assert(is_block_diagonal(models::Ins15Model::reset_blocks));
  static_assert(!is_block_diagonal(models::Ins15Model::transition_blocks));
  // Only the lower triangle of the input is read: garbage above it must not matter.
  SquareMatrix<15> lower = P;
  lower.triangularView<Eigen::StrictlyUpper>().setConstant(std::numeric_limits<double>::quiet_NaN());
  block_diagonal_congruence_lower_in_place<models::Ins15Model::reset_blocks>(G, lower);
  for (int j = 0; j < 15; ++j)
    for (int i = j; i < 15; ++i) EXPECT_NEAR(lower(i, j), dense(i, j), 1e-12) << i << "," << j;
  // A diagonal-kind block (scaling) as well: the pattern of the bias decay in F.
  static constexpr auto scaled = block_pattern<L>({{"p", "p", kIdentity}, {"v", "v", kIdentity}, {"theta", "theta"},
                                                    {"bg", "bg", kDiagonal}, {"ba", "ba", kIdentity}});
  SquareMatrix<15> G2 = G;
  L::cov<"bg">(G2).diagonal() << 0.9, 0.8, 0.7;
  const Eigen::MatrixXd dense2 = Eigen::MatrixXd(G2) * Eigen::MatrixXd(P) * Eigen::MatrixXd(G2).transpose();
  SquareMatrix<15> lower2 = P;
  block_diagonal_congruence_lower_in_place<scaled>(G2, lower2);
  for (int j = 0; j < 15; ++j)
    for (int i = j; i < 15; ++i) EXPECT_NEAR(lower2(i, j), dense2(i, j), 1e-12) << i << "," << j;
}

TEST(BlockSparsity, LowerCongruenceLeavesTheUpperTriangleAlone) {
  const SquareMatrix<15> F = ins_transition(models::Ins15Model{});
  const SquareMatrix<15> P = random_covariance();
  const Eigen::MatrixXd dense = Eigen::MatrixXd(F) * Eigen::MatrixXd(P) * Eigen::MatrixXd(F).transpose();
  SquareMatrix<15> out = SquareMatrix<15>::Constant(-7.0);
  congruence_lower<models::Ins15Model::transition_blocks>(F, P, out);
  for (int j = 0; j < 15; ++j)
    for (int i = 0; i < 15; ++i) {
      // Block-lower: rows of a block at or below the block of the column are computed.
      if (i / 3 >= j / 3) EXPECT_NEAR(out(i, j), dense(i, j), 1e-12) << i << "," << j;
      else EXPECT_EQ(out(i, j), -7.0) << i << "," << j;
    }
}

// The same model without its patterns: the filter must give the same answer either way.
struct DenseInsModel {
  using State = models::InsState;
  using Input = models::ImuSample;
  static constexpr int dim = 15;
  models::Ins15Model m;
  State predict(const State& x, const Input& u, double dt, SquareMatrix<15>* F) const { return m.predict(x, u, dt, F); }
  SquareMatrix<15> noise(const State& x, const Input& u, double dt) const { return m.noise(x, u, dt); }
  State inject(const State& x, const Vector<15>& dx) const { return m.inject(x, dx); }
  Vector<15> difference(const State& a, const State& b) const { return m.difference(a, b); }
  SquareMatrix<15> reset_jacobian(const State& x, const Vector<15>& dx) const { return m.reset_jacobian(x, dx); }
};
struct DenseGnss {
  static constexpr int dim = 3;
  models::GnssPosition<> g;
  Vector<3> predict(const models::InsState& x, Matrix<3, 15>* H) const { return g.predict(x, H); }
  SquareMatrix<3> noise(const models::InsState& x) const { return g.noise(x); }
};

TEST(BlockSparsity, FilterResultsDoNotDependOnDeclaredPatterns) {
  models::Ins15Model sparse;
  DenseInsModel dense{sparse};
  models::GnssPosition<> g;
  g.lever_arm = {0.3, -0.2, 1.1};
  g.R = SquareMatrix<3>::Identity() * 0.3;
  DenseGnss dg{g};
  eskf::Belief<models::Ins15Model> b;
  b.nominal = state();
  b.cov = SquareMatrix<15>::Identity() * 0.05;
  Eskf<models::Ins15Model> fs(sparse, b);
  Eskf<DenseInsModel> fd(dense, b);
  models::ImuSample u;
  for (int k = 0; k < 300; ++k) {
    u.gyro = {0.05 * std::sin(0.1 * k), 0.02, 0.1};
    u.accel = {0.5 * std::cos(0.05 * k), 0.1, 9.8};
    ASSERT_TRUE(fs.predict(u, 0.01));
    ASSERT_TRUE(fd.predict(u, 0.01));
    if (k % 10 == 0) {
      const Vector<3> z(3.0 + 0.05 * k, 4.0, 5.5);
      ASSERT_TRUE(fs.update(g, z));
      ASSERT_TRUE(fd.update(dg, z));
    }
  }
  EXPECT_LT((fs.belief().cov - fd.belief().cov).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT(sparse.difference(fs.nominal(), fd.nominal()).cwiseAbs().maxCoeff(), 1e-12);
}

// A pattern over uneven blocks with every kind, an identity and a diagonal block that are not
// first in their row, a block row with no block and blocks above the block diagonal: the
// plain-loop congruence (which skips the rows of P A' it never reads) against the dense
// formula on random inputs.
TEST(BlockSparsity, CongruenceOnAnIrregularPatternEqualsDense) {
  using UL = Layout<StateBlock<"a", 2>, StateBlock<"b", 3>, StateBlock<"c", 1>, StateBlock<"d", 4>>;
  static constexpr auto pat = block_pattern<UL>({{"a", "c"}, {"a", "a", kIdentity}, {"b", "a"}, {"b", "d"},
                                                 {"b", "b", kDiagonal}, {"d", "b"}, {"d", "d", kIdentity}});
  constexpr int N = UL::size;
  std::srand(41);
  for (int trial = 0; trial < 5; ++trial) {
    SquareMatrix<N> F = SquareMatrix<N>::Zero();
    for (std::size_t k = 0; k < decltype(pat)::size; ++k) {
      const auto rb = static_cast<std::size_t>(pat.row[k]), cb = static_cast<std::size_t>(pat.col[k]);
      auto blk = F.block(UL::offsets[rb], UL::offsets[cb], UL::sizes[rb], UL::sizes[cb]);
      if (pat.kind[k] == BlockKind::identity) blk.setIdentity();
      else if (pat.kind[k] == BlockKind::diagonal) blk.diagonal().setRandom();
      else blk.setRandom();
    }
    const SquareMatrix<N> B = SquareMatrix<N>::Random();
    const SquareMatrix<N> P = B * B.transpose() + SquareMatrix<N>::Identity();
    const Eigen::MatrixXd dense = Eigen::MatrixXd(F) * Eigen::MatrixXd(P) * Eigen::MatrixXd(F).transpose();
    const double scale = dense.cwiseAbs().maxCoeff();
    EXPECT_LT((congruence<pat>(F, P) - dense).cwiseAbs().maxCoeff(), 1e-12 * scale);
    SquareMatrix<N> out = SquareMatrix<N>::Constant(-3.0);
    congruence_lower<pat>(F, P, out);
    const auto block_of = [](int i) {
      int b = 0;
      while (b + 1 < static_cast<int>(UL::names.size()) && UL::offsets[static_cast<std::size_t>(b) + 1] <= i) ++b;
      return b;
    };
    for (int j = 0; j < N; ++j)
      for (int i = 0; i < N; ++i) {
        if (block_of(i) >= block_of(j)) EXPECT_NEAR(out(i, j), dense(i, j), 1e-12 * scale) << i << "," << j;
        else EXPECT_EQ(out(i, j), -3.0) << i << "," << j;
      }
  }
}

}  // namespace

// Compile-time block sparsity of Jacobians, in terms of a layout's named blocks. A model that
// knows its transition Jacobian F, its measurement Jacobian H or its reset Jacobian G is zero
// outside a few blocks says so once, e.g.
//
//   static constexpr auto transition_blocks = block_pattern<L>({{"p", "p", kIdentity},
//                                                               {"p", "v"}, ...});
//   static constexpr auto jacobian_columns = column_pattern<L>({"p", "theta"});
//
// and the filters multiply only those blocks. For the 15-state INS this roughly halves the
// arithmetic of F P F' and removes nearly all of G P G' and of the P H' products. Models that
// declare nothing get dense products; the result is the same either way.
#pragma once

#include <array>
#include <cstddef>
#include <string_view>
#include <utility>

#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse {

enum class BlockKind : unsigned char {
  dense,
  diagonal,  // zero off its diagonal (e.g. dt I, or a decay factor per bias): scaled rows
  identity,  // exactly I: copied, not multiplied
};
inline constexpr BlockKind kIdentity = BlockKind::identity;
inline constexpr BlockKind kDiagonal = BlockKind::diagonal;

struct NamedBlock {
  std::string_view row;
  std::string_view col;
  BlockKind kind = BlockKind::dense;
};

template <class L, std::size_t K>
struct BlockPattern {
  using layout = L;
  static constexpr std::size_t size = K;
  std::array<int, K> row{};
  std::array<int, K> col{};
  std::array<BlockKind, K> kind{};
};

template <class L, std::size_t K>
struct ColumnPattern {
  using layout = L;
  static constexpr std::size_t size = K;
  std::array<int, K> block{};
};

namespace detail {
// Not constexpr: a pattern whose evaluation reaches one fails to compile, naming it.
inline void block_name_not_in_layout() {}
inline void identity_or_diagonal_block_not_square() {}
}  // namespace detail

/// Non-zero blocks of a square Jacobian over layout L, evaluated at compile time only: a name
/// that is not in L, or an identity or diagonal block that is not square, does not compile.
template <class L, std::size_t K>
consteval BlockPattern<L, K> block_pattern(const NamedBlock (&blocks)[K]) {
  BlockPattern<L, K> p;
  for (std::size_t k = 0; k < K; ++k) {
    p.row[k] = L::index_of(blocks[k].row);
    p.col[k] = L::index_of(blocks[k].col);
    if (p.row[k] < 0 || p.col[k] < 0) detail::block_name_not_in_layout();
    p.kind[k] = blocks[k].kind;
    if (blocks[k].kind != BlockKind::dense &&
        L::sizes[static_cast<std::size_t>(p.row[k])] != L::sizes[static_cast<std::size_t>(p.col[k])])
      detail::identity_or_diagonal_block_not_square();
  }
  return p;
}

/// Blocks of the state that a measurement Jacobian (rows = measurement) may touch; compile time
/// only, a name not in L does not compile.
template <class L, std::size_t K>
consteval ColumnPattern<L, K> column_pattern(const std::string_view (&names)[K]) {
  ColumnPattern<L, K> p;
  for (std::size_t k = 0; k < K; ++k) {
    p.block[k] = L::index_of(names[k]);
    if (p.block[k] < 0) detail::block_name_not_in_layout();
  }
  return p;
}

namespace detail {
template <auto Pat>
constexpr auto first_block_in_row() {
  std::array<bool, decltype(Pat)::size> first{};
  for (std::size_t k = 0; k < first.size(); ++k) {
    first[k] = true;
    for (std::size_t j = 0; j < k; ++j)
      if (Pat.row[j] == Pat.row[k]) first[k] = false;
  }
  return first;
}
template <auto Pat>
constexpr auto block_rows_with_blocks() {
  using L = typename decltype(Pat)::layout;
  std::array<bool, L::names.size()> has{};
  for (std::size_t k = 0; k < decltype(Pat)::size; ++k) has[static_cast<std::size_t>(Pat.row[k])] = true;
  return has;
}
}  // namespace detail

/// True when every block of the pattern sits on the block diagonal (e.g. a reset Jacobian that
/// only touches the attitude block).
template <class P>
constexpr bool is_block_diagonal(const P& pat) {
  for (std::size_t k = 0; k < P::size; ++k)
    if (pat.row[k] != pat.col[k]) return false;
  return true;
}

/// out = A B for a square A with block pattern `Pat` (zero elsewhere) and any B with A's rows.
template <auto Pat, class DerivedA, class DerivedB, class DerivedOut>
void block_sparse_product(const Eigen::MatrixBase<DerivedA>& A, const Eigen::MatrixBase<DerivedB>& B,
                          Eigen::MatrixBase<DerivedOut>& out) {
  using L = typename decltype(Pat)::layout;
  // The first block of each block row assigns, later ones accumulate, and block rows with no
  // block are zeroed: no pass over the whole output is wasted on zeros.
  static constexpr auto first_in_row = detail::first_block_in_row<Pat>();
  [[maybe_unused]] static constexpr auto row_has_block = detail::block_rows_with_blocks<Pat>();
  detail::static_for<L::names.size()>([&](auto rb) {
    if constexpr (!row_has_block[rb]) out.template middleRows<L::sizes[rb]>(L::offsets[rb]).setZero();
  });
  detail::static_for<decltype(Pat)::size>([&](auto k) {
    constexpr std::size_t rb = static_cast<std::size_t>(Pat.row[k]);
    constexpr std::size_t cb = static_cast<std::size_t>(Pat.col[k]);
    constexpr int r0 = L::offsets[rb], rs = L::sizes[rb], c0 = L::offsets[cb], cs = L::sizes[cb];
    auto dst = out.template middleRows<rs>(r0);
    const auto src = B.template middleRows<cs>(c0);
    if constexpr (Pat.kind[k] == BlockKind::identity) {
      if constexpr (first_in_row[k]) dst = src; else dst += src;
    } else if constexpr (Pat.kind[k] == BlockKind::diagonal) {
      const auto d = A.template block<rs, cs>(r0, c0).diagonal().asDiagonal();
      if constexpr (first_in_row[k]) dst.noalias() = d * src; else dst.noalias() += d * src;
    } else {
      // lazyProduct: a 3x3 block times a 3x15 slice is past Eigen's size threshold for
      // coefficient-based products and would otherwise go through its blocked GEMM.
      const auto a = A.template block<rs, cs>(r0, c0);
      if constexpr (first_in_row[k]) dst.noalias() = a.lazyProduct(src); else dst.noalias() += a.lazyProduct(src);
    }
  });
}

/// P H' for an H (M x N) whose non-zero columns are the blocks of `Pat`.
template <auto Pat, int N, int M>
Matrix<N, M> times_transpose_columns(const SquareMatrix<N>& P, const Matrix<M, N>& H) {
  using L = typename decltype(Pat)::layout;
  Matrix<N, M> out;
  detail::static_for<decltype(Pat)::size>([&](auto k) {
    constexpr std::size_t b = static_cast<std::size_t>(Pat.block[k]);
    constexpr int o = L::offsets[b], s = L::sizes[b];
    const auto term = P.template middleCols<s>(o).lazyProduct(H.template middleCols<s>(o).transpose());
    if constexpr (decltype(k)::value == 0) out.noalias() = term; else out.noalias() += term;
  });
  if constexpr (decltype(Pat)::size == 0) out.setZero();
  return out;
}

/// H X for an H with column pattern `Pat` and X with N rows.
template <auto Pat, int M, int N, int C>
Matrix<M, C> columns_times(const Matrix<M, N>& H, const Matrix<N, C>& X) {
  using L = typename decltype(Pat)::layout;
  Matrix<M, C> out;
  detail::static_for<decltype(Pat)::size>([&](auto k) {
    constexpr std::size_t b = static_cast<std::size_t>(Pat.block[k]);
    constexpr int o = L::offsets[b], s = L::sizes[b];
    const auto term = H.template middleCols<s>(o).lazyProduct(X.template middleRows<s>(o));
    if constexpr (decltype(k)::value == 0) out.noalias() = term; else out.noalias() += term;
  });
  if constexpr (decltype(Pat)::size == 0) out.setZero();
  return out;
}

namespace detail {
/// For each block column c of the block-lower part of A P A', the first block row of
/// T = P A' that the second pass reads: the smallest k over the pattern's blocks (r, k) with
/// r >= c (the block count when there is none). Rows above it are never computed.
template <auto Pat>
constexpr auto first_read_block_of_t() {
  using L = typename decltype(Pat)::layout;
  constexpr int blocks = static_cast<int>(L::names.size());
  std::array<int, L::names.size()> first{};
  for (int c = 0; c < blocks; ++c) {
    int m = blocks;
    for (std::size_t k = 0; k < decltype(Pat)::size; ++k)
      if (Pat.row[k] >= c && Pat.col[k] < m) m = Pat.col[k];
    first[static_cast<std::size_t>(c)] = m;
  }
  return first;
}
}  // namespace detail

/// The block-lower part of A P A' (every block (r, c) of the layout with r >= c, diagonal
/// blocks whole) for a square A with block pattern `Pat` and a symmetric P; blocks above the
/// block diagonal are left as they were. Two passes:
///   T = P A'  by block columns (P's columns are contiguous, so these are long axpys), only
///             from the first row the second pass reads (for a block-triangular-ish A such
///             as the INS transition, T is needed only on and below its block diagonal), then
///   A T       by block rows, each only as far as the block diagonal.
/// Fixed-length column segments with the terms of one block summed in registers, and plain
/// loops over compile-time bounds for the second pass: fewer instructions than Eigen's
/// block-times-block products of these shapes.
template <auto Pat, int N>
void congruence_lower(const SquareMatrix<N>& A, const SquareMatrix<N>& P, SquareMatrix<N>& out) {
  using L = typename decltype(Pat)::layout;
  static_assert(L::size == N);
  [[maybe_unused]] static constexpr auto first_in_row = detail::first_block_in_row<Pat>();
  [[maybe_unused]] static constexpr auto row_has_block = detail::block_rows_with_blocks<Pat>();
  [[maybe_unused]] static constexpr auto first_read = detail::first_read_block_of_t<Pat>();
  SquareMatrix<N> T;
  const double* t = T.data();
  detail::static_for<L::names.size()>([&](auto rb) {
    constexpr int from = first_read[rb] < static_cast<int>(L::names.size()) ? L::offsets[first_read[rb]] : N;
    if constexpr (!row_has_block[rb] && from < N)
      T.template block<N - from, L::sizes[rb]>(from, L::offsets[rb]).setZero();
  });
  // T_{:, r} = sum over blocks (r, c) of A of P_{:, c} A_{rc}'
  detail::static_for<decltype(Pat)::size>([&](auto k) {
    constexpr std::size_t rb = static_cast<std::size_t>(Pat.row[k]);
    constexpr std::size_t cb = static_cast<std::size_t>(Pat.col[k]);
    constexpr int r0 = L::offsets[rb], rs = L::sizes[rb], c0 = L::offsets[cb], cs = L::sizes[cb];
    constexpr int from = first_read[rb] < static_cast<int>(L::names.size()) ? L::offsets[first_read[rb]] : N;
    constexpr bool assign = first_in_row[k];
    constexpr int len = N - from;
    if constexpr (len > 0) {
      // Fixed-length column segments, unrolled, the terms of the block summed in registers.
      for (int a = 0; a < rs; ++a) {
        auto tc = T.col(r0 + a).template segment<len>(from);
        if constexpr (Pat.kind[k] == BlockKind::identity) {
          const auto pc = P.col(c0 + a).template segment<len>(from);
          if constexpr (assign) tc = pc; else tc += pc;
        } else if constexpr (Pat.kind[k] == BlockKind::diagonal) {
          const auto pc = P.col(c0 + a).template segment<len>(from);
          const double f = A(r0 + a, c0 + a);
          if constexpr (assign) tc = f * pc; else tc += f * pc;
        } else {
          Vector<len> sum = A(r0 + a, c0) * P.col(c0).template segment<len>(from);
          for (int b = 1; b < cs; ++b) sum += A(r0 + a, c0 + b) * P.col(c0 + b).template segment<len>(from);
          if constexpr (assign) tc = sum; else tc += sum;
        }
      }
    }
  });
  detail::static_for<L::names.size()>([&](auto rb) {
    if constexpr (!row_has_block[rb])
      out.template block<L::sizes[rb], L::offsets[rb] + L::sizes[rb]>(L::offsets[rb], 0).setZero();
  });
  // (A T)_{r, 0..r} = sum over blocks (r, c) of A of A_{rc} T_{c, 0..r}
  double* o = out.data();
  detail::static_for<decltype(Pat)::size>([&](auto k) {
    constexpr std::size_t rb = static_cast<std::size_t>(Pat.row[k]);
    constexpr std::size_t cb = static_cast<std::size_t>(Pat.col[k]);
    constexpr int r0 = L::offsets[rb], rs = L::sizes[rb], c0 = L::offsets[cb], cs = L::sizes[cb];
    constexpr int width = r0 + rs;
    constexpr bool assign = first_in_row[k];
    if constexpr (Pat.kind[k] == BlockKind::identity) {
      for (int j = 0; j < width; ++j)
        for (int a = 0; a < rs; ++a) {
          double& dst = o[j * N + r0 + a];
          dst = assign ? t[j * N + c0 + a] : dst + t[j * N + c0 + a];
        }
    } else if constexpr (Pat.kind[k] == BlockKind::diagonal) {
      double f[rs];
      for (int a = 0; a < rs; ++a) f[a] = A(r0 + a, c0 + a);
      for (int j = 0; j < width; ++j)
        for (int a = 0; a < rs; ++a) {
          double& dst = o[j * N + r0 + a];
          dst = assign ? f[a] * t[j * N + c0 + a] : dst + f[a] * t[j * N + c0 + a];
        }
    } else {
      double f[rs][cs];
      for (int a = 0; a < rs; ++a)
        for (int b = 0; b < cs; ++b) f[a][b] = A(r0 + a, c0 + b);
      for (int j = 0; j < width; ++j) {
        const double* tc = t + j * N + c0;
        for (int a = 0; a < rs; ++a) {
          double sum = assign ? 0.0 : o[j * N + r0 + a];
          for (int b = 0; b < cs; ++b) sum += f[a][b] * tc[b];
          o[j * N + r0 + a] = sum;
        }
      }
    }
  });
}

/// A P A' for a square A with block pattern `Pat` and a symmetric P.
template <auto Pat, int N>
SquareMatrix<N> congruence(const SquareMatrix<N>& A, const SquareMatrix<N>& P) {
  SquareMatrix<N> out;
  congruence_lower<Pat>(A, P, out);
  symmetrize(out);
  return out;
}

/// The lower triangle of A P A' in place, for a block-diagonal pattern, reading only the lower
/// triangle of the symmetric P (so a covariance that is only valid below its diagonal needs
/// no mirroring first). Block (r, c), r >= c, of the result is A_r P_rc A_c'; for each
/// non-identity diagonal block b that is A_b times the part of block row b left of the
/// diagonal block, the part of block column b below it times A_b', and A_b P_bb A_b' for the
/// diagonal block itself. The strict upper triangle is left unspecified.
template <auto Pat, int N>
void block_diagonal_congruence_lower_in_place(const SquareMatrix<N>& A, SquareMatrix<N>& P) {
  using L = typename decltype(Pat)::layout;
  static_assert(L::size == N);
  static_assert(is_block_diagonal(Pat), "block_diagonal_congruence_lower_in_place needs a block-diagonal pattern");
  detail::static_for<decltype(Pat)::size>([&](auto k) {
    constexpr std::size_t b = static_cast<std::size_t>(Pat.row[k]);
    constexpr int o = L::offsets[b], s = L::sizes[b], below = N - o - s;
    if constexpr (Pat.kind[k] == BlockKind::diagonal) {
      const auto d = A.template block<s, s>(o, o).diagonal().asDiagonal();
      P.template block<s, o + s>(o, 0) = d * P.template block<s, o + s>(o, 0);
      P.template block<below + s, s>(o, o) = P.template block<below + s, s>(o, o) * d;
    } else if constexpr (Pat.kind[k] == BlockKind::dense) {
      const auto a = A.template block<s, s>(o, o);
      if constexpr (o > 0) {
        const Matrix<s, o> left = a.lazyProduct(P.template block<s, o>(o, 0));
        P.template block<s, o>(o, 0) = left;
      }
      if constexpr (below > 0) {
        const Matrix<below, s> under = P.template block<below, s>(o + s, o).lazyProduct(a.transpose());
        P.template block<below, s>(o + s, o) = under;
      }
      SquareMatrix<s> diag = P.template block<s, s>(o, o);
      symmetrize(diag);
      const SquareMatrix<s> a_diag = a.lazyProduct(diag);
      P.template block<s, s>(o, o).noalias() = a_diag.lazyProduct(a.transpose());
    }
  });
}

}  // namespace ctxfuse

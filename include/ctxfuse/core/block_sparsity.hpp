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
#include <stdexcept>
#include <string_view>
#include <utility>

#include "ctxfuse/core/layout.hpp"
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

/// Non-zero blocks of a square Jacobian over layout L. A name that is not in L is a
/// compile-time error (the throw cannot be evaluated in a constant expression).
template <class L, std::size_t K>
constexpr BlockPattern<L, K> block_pattern(const NamedBlock (&blocks)[K]) {
  BlockPattern<L, K> p;
  for (std::size_t k = 0; k < K; ++k) {
    p.row[k] = L::index_of(blocks[k].row);
    p.col[k] = L::index_of(blocks[k].col);
    if (p.row[k] < 0 || p.col[k] < 0) throw std::logic_error("block name not in layout");
    p.kind[k] = blocks[k].kind;
    if (blocks[k].kind != BlockKind::dense &&
        L::sizes[static_cast<std::size_t>(p.row[k])] != L::sizes[static_cast<std::size_t>(p.col[k])])
      throw std::logic_error("an identity or diagonal block must be square");
  }
  return p;
}

/// Blocks of the state that a measurement Jacobian (rows = measurement) may touch.
template <class L, std::size_t K>
constexpr ColumnPattern<L, K> column_pattern(const std::string_view (&names)[K]) {
  ColumnPattern<L, K> p;
  for (std::size_t k = 0; k < K; ++k) {
    p.block[k] = L::index_of(names[k]);
    if (p.block[k] < 0) throw std::logic_error("block name not in layout");
  }
  return p;
}

namespace detail {
template <std::size_t... I, class F>
constexpr void static_for_impl(std::index_sequence<I...>, F&& f) {
  (f(std::integral_constant<std::size_t, I>{}), ...);
}
template <std::size_t N, class F>
constexpr void static_for(F&& f) {
  static_for_impl(std::make_index_sequence<N>{}, std::forward<F>(f));
}
}  // namespace detail

/// out = A B for a square A with block pattern `Pat` (zero elsewhere) and any B with A's rows.
template <auto Pat, class DerivedA, class DerivedB, class DerivedOut>
void block_sparse_product(const Eigen::MatrixBase<DerivedA>& A, const Eigen::MatrixBase<DerivedB>& B,
                          Eigen::MatrixBase<DerivedOut>& out) {
  using L = typename decltype(Pat)::layout;
  // The first block of each block row assigns, later ones accumulate, and block rows with no
  // block are zeroed: no pass over the whole output is wasted on zeros.
  static constexpr auto first_in_row = [] {
    std::array<bool, decltype(Pat)::size> first{};
    for (std::size_t k = 0; k < first.size(); ++k) {
      first[k] = true;
      for (std::size_t j = 0; j < k; ++j)
        if (Pat.row[j] == Pat.row[k]) first[k] = false;
    }
    return first;
  }();
  [[maybe_unused]] static constexpr auto row_has_block = [] {
    std::array<bool, L::names.size()> has{};
    for (std::size_t k = 0; k < decltype(Pat)::size; ++k) has[static_cast<std::size_t>(Pat.row[k])] = true;
    return has;
  }();
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
      const auto a = A.template block<rs, cs>(r0, c0);
      if constexpr (first_in_row[k]) dst.noalias() = a * src; else dst.noalias() += a * src;
    }
  });
}

/// P H' for an H (M x N) whose non-zero columns are the blocks of `Pat`.
template <auto Pat, int N, int M>
Matrix<N, M> times_transpose_columns(const SquareMatrix<N>& P, const Matrix<M, N>& H) {
  using L = typename decltype(Pat)::layout;
  Matrix<N, M> out = Matrix<N, M>::Zero();
  detail::static_for<decltype(Pat)::size>([&](auto k) {
    constexpr std::size_t b = static_cast<std::size_t>(Pat.block[k]);
    constexpr int o = L::offsets[b], s = L::sizes[b];
    out.noalias() += P.template middleCols<s>(o) * H.template middleCols<s>(o).transpose();
  });
  return out;
}

/// H X for an H with column pattern `Pat` and X with N rows.
template <auto Pat, int M, int N, int C>
Matrix<M, C> columns_times(const Matrix<M, N>& H, const Matrix<N, C>& X) {
  using L = typename decltype(Pat)::layout;
  Matrix<M, C> out = Matrix<M, C>::Zero();
  detail::static_for<decltype(Pat)::size>([&](auto k) {
    constexpr std::size_t b = static_cast<std::size_t>(Pat.block[k]);
    constexpr int o = L::offsets[b], s = L::sizes[b];
    out.noalias() += H.template middleCols<s>(o) * X.template middleRows<s>(o);
  });
  return out;
}

/// A P A' for a square A with block pattern `Pat`: two block-sparse products, (A (A P)')'.
template <auto Pat, int N>
SquareMatrix<N> congruence(const SquareMatrix<N>& A, const SquareMatrix<N>& P) {
  SquareMatrix<N> AP, APAt;
  block_sparse_product<Pat>(A, P, AP);
  block_sparse_product<Pat>(A, AP.transpose(), APAt);  // A (A P)' = A P' A' = A P A' (P symmetric)
  return APAt;
}

}  // namespace ctxfuse

// State layouts: a compile-time list of named blocks ("p" 3, "v" 3, "theta" 3, ...). Each
// block's offset and size are constants, so views by name cost nothing at run time, and two
// layouts can be aligned by their names (a model written for {p, v} applies to a state
// {p, v, theta, bg, ba} without index bookkeeping by hand).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <string_view>

#include "ctxfuse/core/types.hpp"

namespace ctxfuse {

/// A string usable as a template argument: StateBlock<"p", 3>.
template <std::size_t N>
struct FixedString {
  char chars[N]{};
  constexpr FixedString(const char (&s)[N]) { std::copy_n(s, N, chars); }  // NOLINT
  constexpr std::string_view view() const { return {chars, N - 1}; }
};

template <FixedString Name, int Size>
struct StateBlock {
  static_assert(Size > 0, "a state block has at least one element");
  static constexpr std::string_view name = Name.view();
  static constexpr int size = Size;
};

template <class... Blocks>
struct Layout {
  static constexpr int block_count = static_cast<int>(sizeof...(Blocks));
  static constexpr int size = (0 + ... + Blocks::size);
  static constexpr std::array<std::string_view, sizeof...(Blocks)> names{Blocks::name...};
  static constexpr std::array<int, sizeof...(Blocks)> sizes{Blocks::size...};
  static constexpr std::array<int, sizeof...(Blocks)> offsets = [] {
    std::array<int, sizeof...(Blocks)> out{};
    int at = 0;
    for (std::size_t i = 0; i < out.size(); ++i) {
      out[i] = at;
      at += sizes[i];
    }
    return out;
  }();

  static constexpr int index_of(std::string_view name) {
    for (std::size_t i = 0; i < names.size(); ++i)
      if (names[i] == name) return static_cast<int>(i);
    return -1;
  }
  static constexpr bool contains(std::string_view name) { return index_of(name) >= 0; }

  static_assert([] {
    for (std::size_t i = 0; i < names.size(); ++i)
      for (std::size_t j = i + 1; j < names.size(); ++j)
        if (names[i] == names[j]) return false;
    return true;
  }(), "block names in a layout must be unique");

  // consteval: a constexpr function is only guaranteed to be folded in a constant context, and
  // g++ calls index_of (a string search) at run time for every Eigen block view otherwise.
  template <FixedString Name>
  static consteval int offset() {
    static_assert(index_of(Name.view()) >= 0, "no block of that name in this layout");
    return offsets[static_cast<std::size_t>(index_of(Name.view()))];
  }
  template <FixedString Name>
  static consteval int size_of() {
    static_assert(index_of(Name.view()) >= 0, "no block of that name in this layout");
    return sizes[static_cast<std::size_t>(index_of(Name.view()))];
  }

  using StateVector = Vector<size>;
  using CovarianceMatrix = SquareMatrix<size>;

  /// Typed view of block `Name` inside a state vector (read/write when x is mutable).
  template <FixedString Name, class Derived>
  static auto get(Eigen::MatrixBase<Derived>& x) {
    return x.template segment<size_of<Name>()>(offset<Name>());
  }
  template <FixedString Name, class Derived>
  static auto get(const Eigen::MatrixBase<Derived>& x) {
    return x.template segment<size_of<Name>()>(offset<Name>());
  }

  /// Covariance block between blocks `Row` and `Col` (Col defaults to Row).
  template <FixedString Row, FixedString Col = Row, class Derived>
  static auto cov(Eigen::MatrixBase<Derived>& P) {
    return P.template block<size_of<Row>(), size_of<Col>()>(offset<Row>(), offset<Col>());
  }
  template <FixedString Row, FixedString Col = Row, class Derived>
  static auto cov(const Eigen::MatrixBase<Derived>& P) {
    return P.template block<size_of<Row>(), size_of<Col>()>(offset<Row>(), offset<Col>());
  }

  /// Columns of a Jacobian (rows = measurement) that belong to block `Name`.
  template <FixedString Name, class Derived>
  static auto cols(Eigen::MatrixBase<Derived>& H) {
    return H.template middleCols<size_of<Name>()>(offset<Name>());
  }
};

namespace detail {
template <class... Layouts>
struct ConcatImpl;
template <class... A>
struct ConcatImpl<Layout<A...>> {
  using type = Layout<A...>;
};
template <class... A, class... B, class... Rest>
struct ConcatImpl<Layout<A...>, Layout<B...>, Rest...> {
  using type = typename ConcatImpl<Layout<A..., B...>, Rest...>::type;
};
}  // namespace detail

/// Layout with the blocks of each argument in order; names must stay unique.
template <class... Layouts>
using Concat = typename detail::ConcatImpl<Layouts...>::type;

/// Index map from a sub-layout into a full layout by block names: element i of a Sub state
/// sits at element `index[i]` of a Full state. A missing name or a size mismatch is a
/// compile-time error.
template <class Sub, class Full>
struct LayoutMap {
  static constexpr std::array<int, static_cast<std::size_t>(Sub::size)> index = [] {
    std::array<int, static_cast<std::size_t>(Sub::size)> out{};
    std::size_t k = 0;
    for (std::size_t b = 0; b < Sub::names.size(); ++b) {
      const int full_block = Full::index_of(Sub::names[b]);
      for (int e = 0; e < Sub::sizes[b]; ++e)
        out[k++] = Full::offsets[static_cast<std::size_t>(full_block)] + e;
    }
    return out;
  }();

  static_assert([] {
    for (std::size_t b = 0; b < Sub::names.size(); ++b) {
      const int f = Full::index_of(Sub::names[b]);
      if (f < 0 || Full::sizes[static_cast<std::size_t>(f)] != Sub::sizes[b]) return false;
    }
    return true;
  }(), "every block of the sub-layout must exist in the full layout with the same size");

  template <class Derived>
  static Vector<Sub::size, typename Derived::Scalar> extract(const Eigen::MatrixBase<Derived>& full) {
    Vector<Sub::size, typename Derived::Scalar> out;
    for (int i = 0; i < Sub::size; ++i) out(i) = full(index[static_cast<std::size_t>(i)]);
    return out;
  }

  template <class DerivedSub, class DerivedFull>
  static void insert(const Eigen::MatrixBase<DerivedSub>& sub, Eigen::MatrixBase<DerivedFull>& full) {
    for (int i = 0; i < Sub::size; ++i) full(index[static_cast<std::size_t>(i)]) = sub(i);
  }

  /// Rows x Sub Jacobian -> Rows x Full Jacobian with zeros in the columns Sub does not have.
  template <int Rows, class Scalar>
  static Matrix<Rows, Full::size, Scalar> widen_columns(const Matrix<Rows, Sub::size, Scalar>& J) {
    Matrix<Rows, Full::size, Scalar> out = Matrix<Rows, Full::size, Scalar>::Zero();
    for (int i = 0; i < Sub::size; ++i) out.col(index[static_cast<std::size_t>(i)]) = J.col(i);
    return out;
  }

  template <class Derived>
  static SquareMatrix<Sub::size, typename Derived::Scalar> extract_cov(const Eigen::MatrixBase<Derived>& P) {
    SquareMatrix<Sub::size, typename Derived::Scalar> out;
    for (int i = 0; i < Sub::size; ++i)
      for (int j = 0; j < Sub::size; ++j)
        out(i, j) = P(index[static_cast<std::size_t>(i)], index[static_cast<std::size_t>(j)]);
    return out;
  }
};

}  // namespace ctxfuse

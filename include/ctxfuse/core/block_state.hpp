// A nominal state keyed by a layout's block names, with one retraction per block. Each block
// says how its error enters (x [+] dx), how two values differ (a [-] b) and how an error about
// the old value maps to one about the new value after a correction (the reset Jacobian); the
// state's inject, difference and reset Jacobian are these, block by block. Adding a block to a
// state (an augmentation: lever arm, mounting angles, scale factors) is adding a block and a
// retraction, not rewriting the model's retraction.
//
//   using S = BlockState<Layout<StateBlock<"p", 3>, StateBlock<"theta", 3>>, VectorRetraction<3>, So3Retraction>;
//   S x;  x.get<"theta">() = Eigen::Quaterniond::Identity();
//   S y = block_inject(x, dx);  Vector<6> d = block_difference(y, x);   // == dx
#pragma once

#include <cmath>
#include <numbers>
#include <tuple>
#include <utility>

#include "ctxfuse/core/block_sparsity.hpp"
#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/core/numerics.hpp"
#include "ctxfuse/core/so3.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse {

/// A Euclidean block: x [+] dx = x + dx; the reset Jacobian is the identity.
template <int N>
struct VectorRetraction {
  static constexpr int dim = N;
  static constexpr BlockKind reset_kind = BlockKind::identity;
  using Value = Vector<N>;
  static Value identity() { return Value::Zero(); }
  static Value inject(const Value& x, const Vector<N>& dx) { return x + dx; }
  static Vector<N> difference(const Value& a, const Value& b) { return a - b; }
  static SquareMatrix<N> reset_jacobian(const Value&, const Vector<N>&) { return SquareMatrix<N>::Identity(); }
  static bool is_finite(const Value& x) { return all_finite(x); }
};

/// A rotation as a unit quaternion with the error on the right (body-frame error):
/// q [+] e = q Exp(e). After injecting dx an error e about q maps to Jr(dx) e about q Exp(dx)
/// (Exp(dx + e) ~= Exp(dx) Exp(Jr(dx) e)).
struct So3Retraction {
  static constexpr int dim = 3;
  static constexpr BlockKind reset_kind = BlockKind::dense;
  using Value = Eigen::Quaterniond;
  static Value identity() { return Value::Identity(); }
  static Value inject(const Value& q, const Vector<3>& e) { return (q * so3::exp_quat(e)).normalized(); }
  static Vector<3> difference(const Value& a, const Value& b) { return so3::log(Eigen::Quaterniond(b.conjugate() * a)); }
  static SquareMatrix<3> reset_jacobian(const Value&, const Vector<3>& dx) { return so3::right_jacobian(dx); }
  static bool is_finite(const Value& q) { return all_finite(q.coeffs()); }
};

/// An angle on the circle [rad], kept in (-pi, pi]; differences wrapped likewise.
struct PlanarAngleRetraction {
  static constexpr int dim = 1;
  static constexpr BlockKind reset_kind = BlockKind::identity;
  using Value = Vector<1>;
  static double wrap(double a) {
    a = std::remainder(a, 2.0 * std::numbers::pi);
    return a <= -std::numbers::pi ? a + 2.0 * std::numbers::pi : a;
  }
  static Value identity() { return Value::Zero(); }
  static Value inject(const Value& x, const Vector<1>& dx) { return Value(wrap(x(0) + dx(0))); }
  static Vector<1> difference(const Value& a, const Value& b) { return Vector<1>(wrap(a(0) - b(0))); }
  static SquareMatrix<1> reset_jacobian(const Value&, const Vector<1>&) { return SquareMatrix<1>::Identity(); }
  static bool is_finite(const Value& x) { return all_finite(x); }
};

template <class L, class... Retractions>
struct BlockState {
  static_assert(sizeof...(Retractions) == L::names.size(), "one retraction per block");
  static_assert([] {
    constexpr int dims[] = {Retractions::dim...};
    for (std::size_t i = 0; i < L::sizes.size(); ++i)
      if (dims[i] != L::sizes[i]) return false;
    return true;
  }(), "each retraction's dimension is its block's size");
  using ErrorLayout = L;
  static constexpr int dim = L::size;
  using Values = std::tuple<typename Retractions::Value...>;
  Values values{Retractions::identity()...};

  template <FixedString Name>
  auto& get() {
    return std::get<static_cast<std::size_t>(L::index_of(Name.view()))>(values);
  }
  template <FixedString Name>
  const auto& get() const {
    return std::get<static_cast<std::size_t>(L::index_of(Name.view()))>(values);
  }
  static constexpr bool has(std::string_view name) { return L::contains(name); }
};

namespace detail {
template <class S>
struct BlockStateTraits;
template <class L, class... R>
struct BlockStateTraits<BlockState<L, R...>> {
  using retractions = std::tuple<R...>;
};
template <class S, std::size_t I>
using RetractionAt = std::tuple_element_t<I, typename BlockStateTraits<S>::retractions>;
}  // namespace detail

template <class S>
S block_inject(const S& x, const Vector<S::dim>& dx) {
  using L = typename S::ErrorLayout;
  S out;
  detail::static_for<L::names.size()>([&](auto b) {
    using R = detail::RetractionAt<S, b>;
    std::get<b>(out.values) = R::inject(std::get<b>(x.values), dx.template segment<R::dim>(L::offsets[b]));
  });
  return out;
}

template <class S>
Vector<S::dim> block_difference(const S& a, const S& b_state) {
  using L = typename S::ErrorLayout;
  Vector<S::dim> d;
  detail::static_for<L::names.size()>([&](auto b) {
    using R = detail::RetractionAt<S, b>;
    d.template segment<R::dim>(L::offsets[b]) = R::difference(std::get<b>(a.values), std::get<b>(b_state.values));
  });
  return d;
}

/// Block-diagonal d(new error)/d(old error) after injecting dx (see the retractions).
template <class S>
SquareMatrix<S::dim> block_reset_jacobian(const S& x, const Vector<S::dim>& dx) {
  using L = typename S::ErrorLayout;
  SquareMatrix<S::dim> G = SquareMatrix<S::dim>::Zero();
  detail::static_for<L::names.size()>([&](auto b) {
    using R = detail::RetractionAt<S, b>;
    constexpr int o = L::offsets[b];
    G.template block<R::dim, R::dim>(o, o) = R::reset_jacobian(std::get<b>(x.values), dx.template segment<R::dim>(o));
  });
  return G;
}

template <class S>
bool block_is_finite(const S& x) {
  bool ok = true;
  detail::static_for<S::ErrorLayout::names.size()>(
      [&](auto b) { ok = ok && detail::RetractionAt<S, b>::is_finite(std::get<b>(x.values)); });
  return ok;
}

/// The reset Jacobian's block pattern, from each retraction's reset_kind: what the filter's
/// G P G' multiplies (identity blocks are skipped).
template <class S>
constexpr auto block_reset_pattern() {
  using L = typename S::ErrorLayout;
  constexpr std::size_t K = L::names.size();
  BlockPattern<L, K> p;
  detail::static_for<K>([&](auto b) {
    p.row[b] = static_cast<int>(b.value);
    p.col[b] = static_cast<int>(b.value);
    p.kind[b] = detail::RetractionAt<S, b>::reset_kind;
  });
  return p;
}

/// The error-state half of a process model whose state is the BlockState S: a model derives
/// from this (no virtual functions) and writes only predict and noise.
template <class S>
struct BlockRetractionOf {
  S inject(const S& x, const Vector<S::dim>& dx) const { return block_inject(x, dx); }
  Vector<S::dim> difference(const S& a, const S& b) const { return block_difference(a, b); }
  SquareMatrix<S::dim> reset_jacobian(const S& x, const Vector<S::dim>& dx) const { return block_reset_jacobian(x, dx); }
  bool is_finite(const S& x) const { return block_is_finite(x); }
};

}  // namespace ctxfuse

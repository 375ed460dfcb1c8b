// Augmentation of an error-state process model with extra blocks, each a constant or a
// first-order Gauss-Markov process (lever arm, mounting angles, scale factors):
//
//   using Ins20 = Augmented<InsNavModel<>, StateBlock<"mount", 2>, StateBlock<"lever", 3>>;
//
// The state is the base's BlockState with the extra blocks appended (VectorRetraction each),
// so inject/difference/reset Jacobian follow from the blocks; the transition and reset block
// patterns are the base's plus one diagonal (identity) block per extra block; F and Q are the
// base's in the top-left corner and the Gauss-Markov decay and variance of each extra block on
// its diagonal. An extra block with tau = infinity and zero density is a constant. A base that
// offers predict(x, u, dt, F) and noise(x, u, dt, Q) overloads writing into any writable
// Eigen expression (InsNavModel does) fills the corner in place; otherwise its own F and Q are
// copied in.
#pragma once

#include <array>
#include <tuple>

#include "ctxfuse/core/block_state.hpp"
#include "ctxfuse/models/ins.hpp"

namespace ctxfuse::models {

namespace detail {
template <class BaseState, class... Extra>
struct AugmentedStateOf;
template <class L, class... R, class... Extra>
struct AugmentedStateOf<BlockState<L, R...>, Extra...> {
  using layout = Concat<L, Layout<Extra...>>;
  using type = BlockState<layout, R..., VectorRetraction<Extra::size>...>;
};
}  // namespace detail

template <class Base, class... Extra>
struct Augmented : BlockRetractionOf<typename detail::AugmentedStateOf<typename Base::State, Extra...>::type> {
  using BaseState = typename Base::State;
  using State = typename detail::AugmentedStateOf<BaseState, Extra...>::type;
  using ErrorLayout = typename State::ErrorLayout;
  using Input = typename Base::Input;
  static constexpr int base_dim = Base::dim;
  static constexpr int dim = ErrorLayout::size;
  static constexpr std::size_t base_blocks = Base::ErrorLayout::names.size();
  static constexpr std::size_t extra_blocks = sizeof...(Extra);

  static constexpr auto transition_blocks = [] {
    constexpr auto b = Base::transition_blocks;
    BlockPattern<ErrorLayout, decltype(b)::size + extra_blocks> p;
    for (std::size_t k = 0; k < decltype(b)::size; ++k) {
      p.row[k] = b.row[k];
      p.col[k] = b.col[k];
      p.kind[k] = b.kind[k];
    }
    for (std::size_t e = 0; e < extra_blocks; ++e) {
      const std::size_t k = decltype(b)::size + e;
      p.row[k] = p.col[k] = static_cast<int>(base_blocks + e);
      p.kind[k] = BlockKind::diagonal;
    }
    return p;
  }();
  static constexpr auto reset_blocks = block_reset_pattern<State>();

  Base base;
  /// One process per extra block, in the order of the block list; all constants by default.
  std::array<GaussMarkov, extra_blocks> extra{};

  static BaseState base_part(const State& x) {
    BaseState b;
    ctxfuse::detail::static_for<base_blocks>([&](auto i) { std::get<i>(b.values) = std::get<i>(x.values); });
    return b;
  }
  static void set_base_part(State& x, const BaseState& b) {
    ctxfuse::detail::static_for<base_blocks>([&](auto i) { std::get<i>(x.values) = std::get<i>(b.values); });
  }

  Problem check_input(const Input& u) const {
    if constexpr (requires { { base.check_input(u) } -> std::convertible_to<Problem>; })
      return base.check_input(u);
    else
      return Problem::none;
  }

  State predict(const State& x, const Input& u, double dt, SquareMatrix<dim>* F) const {
    State out;
    if (!F) {
      set_base_part(out, base.predict(base_part(x), u, dt, nullptr));
    } else {
      auto corner = F->template topLeftCorner<base_dim, base_dim>();
      if constexpr (requires { base.predict(base_part(x), u, dt, corner); }) {
        set_base_part(out, base.predict(base_part(x), u, dt, corner));  // the base writes its F in place
      } else {
        SquareMatrix<base_dim> Fb;
        set_base_part(out, base.predict(base_part(x), u, dt, &Fb));
        corner = Fb;
      }
      zero_around_corner(*F);
    }
    ctxfuse::detail::static_for<extra_blocks>([&](auto e) {
      constexpr std::size_t b = base_blocks + e;
      const double k = extra[e].decay(dt);
      std::get<b>(out.values) = k * std::get<b>(x.values);
      if (F) F->template block<ErrorLayout::sizes[b], ErrorLayout::sizes[b]>(ErrorLayout::offsets[b], ErrorLayout::offsets[b])
                 .diagonal()
                 .setConstant(k);
    });
    return out;
  }

  SquareMatrix<dim> noise(const State& x, const Input& u, double dt) const {
    SquareMatrix<dim> Q;
    auto corner = Q.template topLeftCorner<base_dim, base_dim>();
    if constexpr (requires { base.noise(base_part(x), u, dt, corner); })
      base.noise(base_part(x), u, dt, corner);  // the base writes its Q in place
    else
      corner = base.noise(base_part(x), u, dt);
    zero_around_corner(Q);
    ctxfuse::detail::static_for<extra_blocks>([&](auto e) {
      constexpr std::size_t b = base_blocks + e;
      Q.template block<ErrorLayout::sizes[b], ErrorLayout::sizes[b]>(ErrorLayout::offsets[b], ErrorLayout::offsets[b])
          .diagonal()
          .setConstant(extra[e].variance(dt));
    });
    return Q;
  }

 private:
  // Everything outside the base's top-left corner (the extra blocks' diagonals are set after).
  static void zero_around_corner(SquareMatrix<dim>& M) {
    M.template topRightCorner<base_dim, dim - base_dim>().setZero();
    M.template bottomRows<dim - base_dim>().setZero();
  }
};

}  // namespace ctxfuse::models

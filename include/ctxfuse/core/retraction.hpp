// a [-] b and x [+] dx for any process model: the model's own difference/inject when it has
// them (wrapped angles, quaternions), plain vector subtraction and addition otherwise. Used
// wherever estimates of several filters are compared or averaged (IMM mixing, federated
// fusion), so that a heading of +179 deg and one of -179 deg are 2 deg apart, not 358.
#pragma once

#include <concepts>

#include "ctxfuse/core/types.hpp"

namespace ctxfuse {

template <class Model>
Vector<Model::dim> state_difference(const Model& m, const typename Model::State& a, const typename Model::State& b) {
  if constexpr (requires { { m.difference(a, b) } -> std::convertible_to<Vector<Model::dim>>; })
    return m.difference(a, b);
  else
    return a - b;
}

template <class Model>
typename Model::State state_inject(const Model& m, const typename Model::State& x, const Vector<Model::dim>& dx) {
  if constexpr (requires { { m.inject(x, dx) } -> std::convertible_to<typename Model::State>; })
    return m.inject(x, dx);
  else
    return x + dx;
}

}  // namespace ctxfuse

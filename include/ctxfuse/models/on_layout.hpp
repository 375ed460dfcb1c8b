// Applies a measurement model written for a small layout to a filter whose state has a larger
// layout, aligning the two by block names (vortex-vkf style): a UWB range model over {p} works
// unchanged in a planar {p, v, psi, bg, ba} filter or a 15-state one.
#pragma once

#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/core/status.hpp"

namespace ctxfuse::models {

template <class Full, class Sub, class Meas>
struct OnLayout {
  using Map = LayoutMap<Sub, Full>;
  static constexpr int dim = Meas::dim;
  Meas inner;

  Vector<dim> predict(const Vector<Full::size>& x, Matrix<dim, Full::size>* H) const {
    const Vector<Sub::size> xs = Map::extract(x);
    if (!H) return inner.predict(xs, nullptr);
    Matrix<dim, Sub::size> Hs;
    const Vector<dim> z = inner.predict(xs, &Hs);
    *H = Map::template widen_columns<dim, double>(Hs);
    return z;
  }
  SquareMatrix<dim> noise(const Vector<Full::size>& x) const { return inner.noise(Map::extract(x)); }

  Vector<dim> residual(const Vector<dim>& z, const Vector<dim>& z_pred) const {
    if constexpr (requires { inner.residual(z, z_pred); })
      return inner.residual(z, z_pred);
    else
      return z - z_pred;
  }
  Problem check(const Vector<dim>& z) const {
    if constexpr (requires { { inner.check(z) } -> std::convertible_to<Problem>; })
      return inner.check(z);
    else
      return Problem::none;
  }
};

template <class Full, class Sub, class Meas>
OnLayout<Full, Sub, Meas> on_layout(Meas m) {
  return OnLayout<Full, Sub, Meas>{std::move(m)};
}

}  // namespace ctxfuse::models

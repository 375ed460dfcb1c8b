// Ceres cost functions from this library's factors, through their templated residuals: the
// one model, differentiated automatically by Ceres (tests and benchmarks only).
#pragma once

#include <ceres/ceres.h>

#include <limits>
#include <memory>

#include "ctxfuse/core/factor.hpp"

namespace ctxfuse::test {

template <class F>
struct UnaryResidual {
  static constexpr int n = F::slot_dims[0];
  F factor;
  template <class T>
  bool operator()(const T* x, T* r) const {
    Eigen::Map<Vector<F::dim, T>>{r} = factor.template residual<T>(Vector<n, T>(Eigen::Map<const Vector<n, T>>{x}));
    return true;
  }
};

template <class F>
struct BinaryResidual {
  static constexpr int n0 = F::slot_dims[0], n1 = F::slot_dims[1];
  F factor;
  template <class T>
  bool operator()(const T* a, const T* b, T* r) const {
    Eigen::Map<Vector<F::dim, T>>{r} = factor.template residual<T>(Vector<n0, T>(Eigen::Map<const Vector<n0, T>>{a}),
                                                                   Vector<n1, T>(Eigen::Map<const Vector<n1, T>>{b}));
    return true;
  }
};

template <UnaryFactor F>
ceres::CostFunction* autodiff_cost(const F& f) {
  return new ceres::AutoDiffCostFunction<UnaryResidual<F>, F::dim, F::slot_dims[0]>(new UnaryResidual<F>{f});
}

template <BinaryFactor F>
ceres::CostFunction* autodiff_cost(const F& f) {
  return new ceres::AutoDiffCostFunction<BinaryResidual<F>, F::dim, F::slot_dims[0], F::slot_dims[1]>(
      new BinaryResidual<F>{f});
}

/// The gaps between Ceres' automatic differentiation of a binary factor at (x0, x1) and its
/// analytic evaluate(): the residuals' largest absolute gap, and each slot's Jacobian's largest
/// gap relative to its largest analytic entry.
struct JacobianGaps {
  double residual = 0.0, slot0 = 0.0, slot1 = 0.0;
};
template <BinaryFactor F>
JacobianGaps jacobian_gaps(const F& f, const Vector<F::slot_dims[0]>& x0, const Vector<F::slot_dims[1]>& x1) {
  constexpr int m = F::dim, n0 = F::slot_dims[0], n1 = F::slot_dims[1];
  std::unique_ptr<ceres::CostFunction> cost(autodiff_cost(f));
  Vector<m> r;
  Eigen::Matrix<double, m, n0, (n0 == 1 ? Eigen::ColMajor : Eigen::RowMajor)> Ja;
  Eigen::Matrix<double, m, n1, (n1 == 1 ? Eigen::ColMajor : Eigen::RowMajor)> Jb;
  const double* params[] = {x0.data(), x1.data()};
  double* jac[] = {Ja.data(), Jb.data()};
  JacobianGaps g;
  if (!cost->Evaluate(params, r.data(), jac)) {
    g.residual = g.slot0 = g.slot1 = std::numeric_limits<double>::infinity();
    return g;
  }
  Matrix<m, n0> A0;
  Matrix<m, n1> A1;
  g.residual = (r - f.evaluate(x0, x1, &A0, &A1)).cwiseAbs().maxCoeff();
  g.slot0 = (Matrix<m, n0>(Ja) - A0).cwiseAbs().maxCoeff() / A0.cwiseAbs().maxCoeff();
  g.slot1 = (Matrix<m, n1>(Jb) - A1).cwiseAbs().maxCoeff() / A1.cwiseAbs().maxCoeff();
  return g;
}

/// The smoother's window as a Ceres problem over states xs (solved in place): the prior,
/// every attached measurement and every motion factor, each as an autodiff cost.
template <class Window, class States>
void add_window(const Window& w, States& xs, ceres::Problem& problem) {
  problem.AddResidualBlock(autodiff_cost(w.prior), nullptr, xs[0].data());
  for (int i = 0; i < w.size; ++i) {
    const auto k = static_cast<std::size_t>(i);
    for (int j = 0; j < w.epochs[k].factor_count; ++j)
      problem.AddResidualBlock(autodiff_cost(w.epochs[k].factors[static_cast<std::size_t>(j)]), nullptr, xs[k].data());
    if (i > 0) problem.AddResidualBlock(autodiff_cost(w.epochs[k].motion), nullptr, xs[k - 1].data(), xs[k].data());
  }
}

/// Tolerances far below the comparison's 1e-6, so that Ceres stops at the minimum.
inline ceres::Solver::Options tight_options() {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::DENSE_QR;
  o.max_num_iterations = 100;
  o.function_tolerance = 1e-16;
  o.gradient_tolerance = 1e-16;
  o.parameter_tolerance = 1e-14;
  o.num_threads = 1;
  return o;
}

}  // namespace ctxfuse::test

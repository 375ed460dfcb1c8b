// Range from a planar tag at a known height to a fixed anchor, as a ranging system reports it
// when it (1) averages the last n raw two-way ranges of that anchor, taken one period T apart,
// and (2) carries a constant bias per anchor (antenna delay and cable calibration left over):
//
//   z = (1/n) sum_{j=0}^{n-1} | (p - j T v, h) - a | + b_i + noise
//
// over blocks "p" (2), "v" (2) and "b" (one bias per anchor slot) of layout L; under constant
// velocity p - j T v is the position j periods before the report. n = 1 and no bias slot
// (bias_slot < 0) is the plain range from a known height (RangeAtHeight in the UWB pipeline).
//
// `value<T>` is templated on the scalar (ceres::Jet flows through it: the factor-graph path
// and the Ceres Jacobian battery use the same function); `predict(x, &H)` is the analytic one.
#pragma once

#include <cmath>
#include <string_view>

#include "ctxfuse/core/block_sparsity.hpp"
#include "ctxfuse/core/layout.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/core/types.hpp"

namespace ctxfuse::models {

template <class L>
struct AveragedRangeWithBias {
  static_assert(L::template size_of<"p">() == 2 && L::template size_of<"v">() == 2);
  static constexpr int dim = 1;
  static constexpr int bias_slots = L::template size_of<"b">();
  static constexpr auto jacobian_columns = column_pattern<L>({std::string_view("p"), std::string_view("v"), std::string_view("b")});

  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();
  double tag_height = 0.0;
  int samples = 1;         // n, raw ranges per report (>= 1)
  double period_s = 0.1;   // T, between raw ranges of one anchor
  int bias_slot = -1;      // index into block "b"; < 0: no bias state for this anchor
  double sigma = 0.1;

  template <class T>
  Vector<1, T> value(const Vector<L::size, T>& x) const {
    const auto p = L::template get<"p">(x);
    const auto v = L::template get<"v">(x);
    using std::sqrt;  // ceres::sqrt for Jets, found by argument-dependent lookup
    T sum = T(0.0);
    for (int j = 0; j < samples; ++j) {
      const T back = T(j * period_s);
      const T dx = p(0) - back * v(0) - T(anchor.x());
      const T dy = p(1) - back * v(1) - T(anchor.y());
      const T dz = T(tag_height - anchor.z());
      sum += sqrt(dx * dx + dy * dy + dz * dz);
    }
    T z = sum / T(static_cast<double>(samples));
    if (bias_slot >= 0) z += L::template get<"b">(x)(bias_slot);
    return Vector<1, T>(z);
  }

  Vector<1> predict(const Vector<L::size>& x, Matrix<1, L::size>* H) const {
    const auto p = L::template get<"p">(x);
    const auto v = L::template get<"v">(x);
    const double inv_n = 1.0 / static_cast<double>(samples);
    double sum = 0.0;
    Eigen::RowVector2d dp = Eigen::RowVector2d::Zero(), dv = Eigen::RowVector2d::Zero();
    for (int j = 0; j < samples; ++j) {
      const double back = j * period_s;
      const Eigen::Vector3d d(p(0) - back * v(0) - anchor.x(), p(1) - back * v(1) - anchor.y(), tag_height - anchor.z());
      const double r = d.norm();
      sum += r;
      // The gradient is undefined on the anchor itself: that sample adds nothing to the row.
      if (r > 0.0) {
        const Eigen::RowVector2d u = d.head<2>().transpose() / r;
        dp += u;
        dv -= back * u;
      }
    }
    double z = sum * inv_n;
    if (bias_slot >= 0) z += L::template get<"b">(x)(bias_slot);
    if (H) {
      H->setZero();
      L::template cols<"p">(*H) = dp * inv_n;
      L::template cols<"v">(*H) = dv * inv_n;
      if (bias_slot >= 0) L::template cols<"b">(*H)(0, bias_slot) = 1.0;
    }
    return Vector<1>(z);
  }

  SquareMatrix<1> noise(const Vector<L::size>&) const { return SquareMatrix<1>(sigma * sigma); }
  Problem check(const Vector<1>& z) const { return z(0) < 0.0 ? Problem::measurement_out_of_domain : Problem::none; }
};

}  // namespace ctxfuse::models

// UWB range on the 15-state INS: z = |p + R(q) l_b - anchor|, the tag at lever arm l_b from
// the IMU. Works with any error layout that has blocks "p" and "theta".
#pragma once

#include "ctxfuse/core/so3.hpp"
#include "ctxfuse/core/status.hpp"
#include "ctxfuse/models/ins.hpp"

namespace ctxfuse::models {

template <class ErrorLayout = Ins15Layout>
struct InsRange {
  static constexpr int dim = 1;
  static constexpr auto jacobian_columns = column_pattern<ErrorLayout>({"p", "theta"});
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();
  Eigen::Vector3d lever_arm = Eigen::Vector3d::Zero();
  double sigma = 0.1;

  Vector<1> predict(const InsState& x, Matrix<1, ErrorLayout::size>* H) const {
    const Eigen::Matrix3d C = x.q.toRotationMatrix();
    const Eigen::Vector3d d = x.p + C * lever_arm - anchor;
    const double r = d.norm();
    if (H) {
      H->setZero();
      if (r > 0.0) {
        const Eigen::RowVector3d u = d.transpose() / r;
        ErrorLayout::template cols<"p">(*H) = u;
        // d(C Exp(e) l)/de = -C [l]x
        ErrorLayout::template cols<"theta">(*H) = -u * C * so3::skew(lever_arm);
      }
    }
    return Vector<1>(r);
  }
  SquareMatrix<1> noise(const InsState&) const { return SquareMatrix<1>(sigma * sigma); }
  Problem check(const Vector<1>& z) const { return z(0) < 0.0 ? Problem::measurement_out_of_domain : Problem::none; }
};

}  // namespace ctxfuse::models

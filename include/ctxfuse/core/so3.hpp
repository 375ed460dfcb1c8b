// Rotation helpers for error-state models: skew, exponential and logarithm maps on SO(3) and
// the right Jacobian. Templated on the scalar (as Sophus is) so that Ceres Jets can flow
// through the same code in the factor-graph smoother.
#pragma once

#include <Eigen/Geometry>
#include <cmath>

namespace ctxfuse::so3 {

template <class Scalar>
using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
template <class Scalar>
using Mat3 = Eigen::Matrix<Scalar, 3, 3>;

template <class Derived>
Mat3<typename Derived::Scalar> skew(const Eigen::MatrixBase<Derived>& v) {
  using S = typename Derived::Scalar;
  Mat3<S> m;
  m << S(0), -v(2), v(1), v(2), S(0), -v(0), -v(1), v(0), S(0);
  return m;
}

/// Unit quaternion of the rotation vector phi (angle |phi| about phi/|phi|).
template <class Derived>
Eigen::Quaternion<typename Derived::Scalar> exp_quat(const Eigen::MatrixBase<Derived>& phi) {
  using S = typename Derived::Scalar;
  using std::cos;
  using std::sin;
  using std::sqrt;
  const S theta2 = phi.squaredNorm();
  if (theta2 < S(1e-16)) {
    // Second-order series; the normalisation keeps it a unit quaternion.
    Eigen::Quaternion<S> q(S(1) - theta2 / S(8), phi(0) / S(2), phi(1) / S(2), phi(2) / S(2));
    q.normalize();
    return q;
  }
  const S theta = sqrt(theta2);
  const S k = sin(theta / S(2)) / theta;
  return Eigen::Quaternion<S>(cos(theta / S(2)), k * phi(0), k * phi(1), k * phi(2));
}

template <class Derived>
Mat3<typename Derived::Scalar> exp(const Eigen::MatrixBase<Derived>& phi) {
  return exp_quat(phi).toRotationMatrix();
}

/// Rotation vector of a unit quaternion, angle in [0, pi].
template <class Scalar>
Vec3<Scalar> log(const Eigen::Quaternion<Scalar>& q_in) {
  using std::atan2;
  using std::sqrt;
  Eigen::Quaternion<Scalar> q = q_in;
  if (q.w() < Scalar(0)) q.coeffs() = -q.coeffs();  // shortest rotation
  const Vec3<Scalar> v = q.vec();
  const Scalar s2 = v.squaredNorm();
  if (s2 < Scalar(1e-16)) return Scalar(2) * v / q.w();
  const Scalar s = sqrt(s2);
  return Scalar(2) * atan2(s, q.w()) / s * v;
}

/// Exp(phi) as a unit quaternion and the right Jacobian Jr(phi) together, from one sine and
/// one cosine of |phi|/2 (sin|phi| = 2 s c, 1 - cos|phi| = 2 s^2): the INS prediction needs
/// both for the same rotation vector, and the trigonometric calls dominate either alone.
template <class Derived>
void exp_quat_and_right_jacobian(const Eigen::MatrixBase<Derived>& phi, Eigen::Quaternion<typename Derived::Scalar>& q,
                                 Mat3<typename Derived::Scalar>& Jr) {
  using S = typename Derived::Scalar;
  using std::cos;
  using std::sin;
  using std::sqrt;
  const S theta2 = phi.squaredNorm();
  const Mat3<S> K = skew(phi);
  if (theta2 < S(1e-10)) {
    q = exp_quat(phi);
    Jr = Mat3<S>::Identity() - K / S(2) + K * K / S(6);
    return;
  }
  const S theta = sqrt(theta2);
  const S s = sin(theta / S(2)), c = cos(theta / S(2));
  const S k = s / theta;
  q = Eigen::Quaternion<S>(c, k * phi(0), k * phi(1), k * phi(2));
  Jr = Mat3<S>::Identity() - (S(2) * s * s) / theta2 * K + (theta - S(2) * s * c) / (theta2 * theta) * K * K;
}

/// Right Jacobian Jr(phi): Exp(phi + d) ~= Exp(phi) Exp(Jr(phi) d). Through the half-angle
/// form above, which keeps the digits that 1 - cos|phi| loses for small angles.
template <class Derived>
Mat3<typename Derived::Scalar> right_jacobian(const Eigen::MatrixBase<Derived>& phi) {
  Eigen::Quaternion<typename Derived::Scalar> q;
  Mat3<typename Derived::Scalar> Jr;
  exp_quat_and_right_jacobian(phi, q, Jr);
  return Jr;
}

/// The inverse of the right Jacobian: Log(Exp(phi) Exp(d)) ~= phi + Jr^-1(phi) d.
///   Jr^-1 = I + [phi]x / 2 + c [phi]x^2,  c = (1 - (t/2) cot(t/2)) / t^2,  t = |phi| < 2 pi,
/// with c's series 1/12 + t^2/720 + t^4/30240 for small t, where the closed form cancels.
template <class Derived>
Mat3<typename Derived::Scalar> right_jacobian_inverse(const Eigen::MatrixBase<Derived>& phi) {
  using S = typename Derived::Scalar;
  using std::cos;
  using std::sin;
  using std::sqrt;
  const S theta2 = phi.squaredNorm();
  const Mat3<S> K = skew(phi);
  S c;
  if (theta2 < S(1e-4)) {
    c = S(1) / S(12) + theta2 / S(720) + theta2 * theta2 / S(30240);
  } else {
    const S theta = sqrt(theta2);
    const S half = theta / S(2);
    c = (S(1) - half * cos(half) / sin(half)) / theta2;
  }
  return Mat3<S>::Identity() + K / S(2) + c * K * K;
}

}  // namespace ctxfuse::so3

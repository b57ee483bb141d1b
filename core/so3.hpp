#pragma once
// SO(3) on Eigen: hat/vee, Exp/Log, the right and left Jacobians and their inverses, and the
// right-perturbation box operators used by the filter (fast-livo2-notes.md §1.2):
//   R ⊞ δ = R·Exp(δ),   R1 ⊟ R0 = Log(R0ᵀ·R1).
// Tangent vectors are rotation vectors φ = θ·a (θ = |φ| in radians, a the unit axis).
//
// Every function is templated on the Eigen expression so that Scalar follows the argument
// (double in livod, float or autodiff types where cheap). Small-angle branches use Taylor series
// up to the order where the truncation error is below the scalar's epsilon; the logarithm has a
// separate branch near θ = π where the antisymmetric part of R vanishes.

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>
#include <limits>
#include <type_traits>

namespace livod::so3 {

template <class Scalar>
using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
template <class Scalar>
using Matrix3 = Eigen::Matrix<Scalar, 3, 3>;

namespace detail {

template <class Derived>
constexpr void require_vector3() {
  static_assert(Derived::RowsAtCompileTime == 3 && Derived::ColsAtCompileTime == 1,
                "expected a 3-vector");
}

template <class Derived>
constexpr void require_matrix3() {
  static_assert(Derived::RowsAtCompileTime == 3 && Derived::ColsAtCompileTime == 3,
                "expected a 3x3 matrix");
}

// Below this angle the closed forms divide tiny numbers by tiny numbers; the Taylor series used
// instead is truncated after the θ² (or θ⁴) term, whose remainder is O(θ⁴) ≈ ε at this angle.
template <class Scalar>
Scalar small_angle() {
  using std::sqrt;
  return sqrt(sqrt(std::numeric_limits<Scalar>::epsilon()));
}

}  // namespace detail

// [v]×, the skew-symmetric matrix with hat(a)·b = a × b.
template <class Derived>
Matrix3<typename Derived::Scalar> hat(const Eigen::MatrixBase<Derived>& v) {
  detail::require_vector3<Derived>();
  using Scalar = typename Derived::Scalar;
  Matrix3<Scalar> m;
  m << Scalar(0), -v(2), v(1),  //
      v(2), Scalar(0), -v(0),   //
      -v(1), v(0), Scalar(0);
  return m;
}

// Inverse of hat(). Reads the antisymmetric part only, so vee(hat(v)) == v exactly and a
// slightly non-skew input is projected rather than read from one triangle.
template <class Derived>
Vector3<typename Derived::Scalar> vee(const Eigen::MatrixBase<Derived>& m) {
  detail::require_matrix3<Derived>();
  using Scalar = typename Derived::Scalar;
  const Scalar half(0.5);
  return Vector3<Scalar>(half * (m(2, 1) - m(1, 2)), half * (m(0, 2) - m(2, 0)),
                         half * (m(1, 0) - m(0, 1)));
}

// Exp: rotation vector -> rotation matrix (Rodrigues).
template <class Derived>
Matrix3<typename Derived::Scalar> exp(const Eigen::MatrixBase<Derived>& phi) {
  detail::require_vector3<Derived>();
  using Scalar = typename Derived::Scalar;
  using std::cos;
  using std::sin;
  using std::sqrt;
  const Scalar theta2 = phi.squaredNorm();
  const Scalar theta = sqrt(theta2);
  const Matrix3<Scalar> k = hat(phi);
  Scalar a;  // sin θ / θ
  Scalar b;  // (1 - cos θ) / θ²
  if (theta < Scalar(0.05)) {
    // Taylor series to θ⁶: the next terms are below 2e-16 here, and the small rotations of
    // undistortion (one per LiDAR point) and propagation skip two trigonometric calls.
    a = Scalar(1) -
        theta2 / Scalar(6) * (Scalar(1) - theta2 / Scalar(20) * (Scalar(1) - theta2 / Scalar(42)));
    b = Scalar(0.5) -
        theta2 / Scalar(24) * (Scalar(1) - theta2 / Scalar(30) * (Scalar(1) - theta2 / Scalar(56)));
  } else {
    a = sin(theta) / theta;
    // 2 sin²(θ/2) instead of 1 - cos θ: no cancellation for moderate angles.
    const Scalar s = sin(theta / Scalar(2));
    b = Scalar(2) * s * s / theta2;
  }
  return Matrix3<Scalar>::Identity() + a * k + b * (k * k);
}

// Log: rotation matrix -> rotation vector with θ in [0, π]. At exactly θ = π both ±φ are valid;
// one of them is returned.
template <class Derived>
Vector3<typename Derived::Scalar> log(const Eigen::MatrixBase<Derived>& r) {
  detail::require_matrix3<Derived>();
  using Scalar = typename Derived::Scalar;
  using std::atan2;
  using std::sqrt;
  // w = vee(R - Rᵀ) = 2 sin θ · a, and trace(R) = 1 + 2 cos θ. atan2 keeps θ accurate over the
  // whole range, unlike acos near 0 and π.
  const Vector3<Scalar> w(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1));
  const Scalar sin_theta = Scalar(0.5) * w.norm();
  const Scalar cos_theta = Scalar(0.5) * (r.trace() - Scalar(1));
  const Scalar theta = atan2(sin_theta, cos_theta);

  if (cos_theta > Scalar(-0.5)) {
    // θ < 120°: φ = θ / (2 sin θ) · w is well conditioned.
    Scalar factor;
    if (theta < detail::small_angle<Scalar>()) {
      factor = Scalar(0.5) + theta * theta / Scalar(12);
    } else {
      factor = theta / (Scalar(2) * sin_theta);
    }
    return factor * w;
  }
  // Near π, w → 0 and loses the axis. The symmetric part keeps it:
  //   (R + Rᵀ)/2 − cos θ·I = (1 − cos θ)·a·aᵀ.
  // Take the column with the largest diagonal entry (|a_j|² ≥ 1/3) and fix the sign with w.
  Matrix3<Scalar> b = Scalar(0.5) * (r + r.transpose());
  b.diagonal().array() -= cos_theta;
  Eigen::Index j = 0;
  b.diagonal().maxCoeff(&j);
  Vector3<Scalar> axis = b.col(j) / sqrt(b(j, j) * (Scalar(1) - cos_theta));
  axis.normalize();
  if (axis.dot(w) < Scalar(0)) axis = -axis;
  return theta * axis;
}

// Right Jacobian: Exp(φ + δ) ≈ Exp(φ)·Exp(Jr(φ)·δ).
//   Jr(φ) = I − (1 − cos θ)/θ²·K + (θ − sin θ)/θ³·K²,  K = hat(φ).
template <class Derived>
Matrix3<typename Derived::Scalar> right_jacobian(const Eigen::MatrixBase<Derived>& phi) {
  detail::require_vector3<Derived>();
  using Scalar = typename Derived::Scalar;
  using std::sin;
  using std::sqrt;
  const Scalar theta2 = phi.squaredNorm();
  const Scalar theta = sqrt(theta2);
  const Matrix3<Scalar> k = hat(phi);
  Scalar a;  // (1 − cos θ)/θ²
  Scalar b;  // (θ − sin θ)/θ³
  if (theta < detail::small_angle<Scalar>()) {
    a = Scalar(0.5) - theta2 / Scalar(24);
    b = Scalar(1) / Scalar(6) - theta2 / Scalar(120);
  } else {
    const Scalar s = sin(theta / Scalar(2));
    a = Scalar(2) * s * s / theta2;
    // The cancellation in θ − sin θ costs ε/θ² relative, but K² is O(θ²): the absolute error
    // of the product stays O(ε).
    b = (theta - sin(theta)) / (theta2 * theta);
  }
  return Matrix3<Scalar>::Identity() - a * k + b * (k * k);
}

// Left Jacobian: Exp(φ + δ) ≈ Exp(Jl(φ)·δ)·Exp(φ). Jl(φ) = Jr(−φ) = Jr(φ)ᵀ. It is also the
// V matrix of SE(3): t = V(φ)·ρ.
template <class Derived>
Matrix3<typename Derived::Scalar> left_jacobian(const Eigen::MatrixBase<Derived>& phi) {
  detail::require_vector3<Derived>();
  return right_jacobian(-phi);
}

// Jr⁻¹(φ) = I + ½K + (1/θ² − cot(θ/2)/(2θ))·K². Finite for θ < 2π (singular at 2π, which Log
// never returns).
template <class Derived>
Matrix3<typename Derived::Scalar> right_jacobian_inverse(const Eigen::MatrixBase<Derived>& phi) {
  detail::require_vector3<Derived>();
  using Scalar = typename Derived::Scalar;
  using std::cos;
  using std::sin;
  using std::sqrt;
  const Scalar theta2 = phi.squaredNorm();
  const Scalar theta = sqrt(theta2);
  const Matrix3<Scalar> k = hat(phi);
  Scalar c;
  if (theta < detail::small_angle<Scalar>()) {
    c = Scalar(1) / Scalar(12) + theta2 / Scalar(720);
  } else {
    // cot(θ/2) written as cos/sin of the half angle: no 0/0 at θ = π, unlike (1 + cos θ)/sin θ.
    const Scalar half = theta / Scalar(2);
    c = (Scalar(1) - half * cos(half) / sin(half)) / theta2;
  }
  return Matrix3<Scalar>::Identity() + Scalar(0.5) * k + c * (k * k);
}

// Jl⁻¹(φ) = Jr⁻¹(−φ). Also V⁻¹ of SE(3).
template <class Derived>
Matrix3<typename Derived::Scalar> left_jacobian_inverse(const Eigen::MatrixBase<Derived>& phi) {
  detail::require_vector3<Derived>();
  return right_jacobian_inverse(-phi);
}

// R ⊞ δ = R·Exp(δ): the perturbation lives in the body frame of R (right perturbation).
template <class DerivedR, class DerivedD>
Matrix3<typename DerivedR::Scalar> boxplus(const Eigen::MatrixBase<DerivedR>& r,
                                           const Eigen::MatrixBase<DerivedD>& delta) {
  detail::require_matrix3<DerivedR>();
  detail::require_vector3<DerivedD>();
  static_assert(std::is_same_v<typename DerivedR::Scalar, typename DerivedD::Scalar>,
                "R and δ must share the scalar type");
  return r * exp(delta);
}

// R1 ⊟ R0 = Log(R0ᵀ·R1), so that R0 ⊞ (R1 ⊟ R0) == R1.
template <class Derived1, class Derived0>
Vector3<typename Derived1::Scalar> boxminus(const Eigen::MatrixBase<Derived1>& r1,
                                            const Eigen::MatrixBase<Derived0>& r0) {
  detail::require_matrix3<Derived1>();
  detail::require_matrix3<Derived0>();
  static_assert(std::is_same_v<typename Derived1::Scalar, typename Derived0::Scalar>,
                "R1 and R0 must share the scalar type");
  return log(r0.transpose() * r1);
}

// Geodesic interpolation R0·Exp(s·Log(R0ᵀR1)); s = 0 gives R0, s = 1 gives R1 (slerp).
template <class Derived0, class Derived1>
Matrix3<typename Derived0::Scalar> interpolate(const Eigen::MatrixBase<Derived0>& r0,
                                               const Eigen::MatrixBase<Derived1>& r1,
                                               typename Derived0::Scalar s) {
  return r0 * exp(s * boxminus(r1, r0));
}

// Rotation angle θ ∈ [0, π] of R, without computing the axis.
template <class Derived>
typename Derived::Scalar angle(const Eigen::MatrixBase<Derived>& r) {
  return log(r).norm();
}

// Nearest rotation matrix (SVD projection); used when a matrix read from a file or accumulated
// over many products has drifted off SO(3).
template <class Derived>
Matrix3<typename Derived::Scalar> orthonormalize(const Eigen::MatrixBase<Derived>& m) {
  detail::require_matrix3<Derived>();
  using Scalar = typename Derived::Scalar;
  const Eigen::JacobiSVD<Matrix3<Scalar>> svd(Matrix3<Scalar>(m),
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  Matrix3<Scalar> d = Matrix3<Scalar>::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < Scalar(0)) d(2, 2) = Scalar(-1);
  return svd.matrixU() * d * svd.matrixV().transpose();
}

}  // namespace livod::so3

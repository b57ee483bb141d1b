#pragma once
// Rigid transforms on Eigen, with two manifold structures on the same (R, p) pair:
//
//  * SE(3) (namespace livod::se3): the Lie group; Exp couples rotation and translation through
//    the V matrix (= the left Jacobian of SO(3)): Exp([φ; ρ]) = (Exp(φ), V(φ)·ρ).
//    T ⊞ ξ = T·Exp(ξ), T1 ⊟ T0 = Log(T0⁻¹·T1). Interpolation follows the screw motion.
//
//  * SO(3)×R³ (namespace livod::so3_r3): the filter's convention (fast-livo2-notes.md §1.2):
//    (R, p) ⊞ [δθ; δp] = (R·Exp(δθ), p + δp). Rotation and translation are perturbed
//    independently, the translation in the parent (world) frame.
//
// Tangent vectors are ordered rotation first, [φ; ρ] / [δθ; δp], matching the filter's state
// order (R at indices 0–2, p at 3–5). Note that Sophus and Barfoot put translation first.
//
// Frames: T_a_b maps coordinates in frame b to frame a, x_a = T_a_b * x_b.

#include <Eigen/Core>
#include <type_traits>

#include "core/so3.hpp"

namespace livod {

template <class Scalar>
struct RigidTransform3 {
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
  using Matrix3 = Eigen::Matrix<Scalar, 3, 3>;
  using Matrix4 = Eigen::Matrix<Scalar, 4, 4>;

  Matrix3 rotation = Matrix3::Identity();
  Vector3 translation = Vector3::Zero();

  RigidTransform3() = default;
  RigidTransform3(const Matrix3& r, const Vector3& p) : rotation(r), translation(p) {}

  static RigidTransform3 identity() { return {}; }

  // From a homogeneous matrix (the bottom row is not checked: callers parse 3x4 files).
  template <class Derived>
  static RigidTransform3 from_matrix(const Eigen::MatrixBase<Derived>& m) {
    return {m.template topLeftCorner<3, 3>(), m.template topRightCorner<3, 1>()};
  }

  [[nodiscard]] Matrix4 matrix() const {
    Matrix4 m = Matrix4::Identity();
    m.template topLeftCorner<3, 3>() = rotation;
    m.template topRightCorner<3, 1>() = translation;
    return m;
  }

  // Uses Rᵀ as the inverse rotation: valid for rotation matrices only.
  [[nodiscard]] RigidTransform3 inverse() const {
    const Matrix3 rt = rotation.transpose();
    return {rt, -(rt * translation)};
  }

  // T_a_c = T_a_b * T_b_c
  friend RigidTransform3 operator*(const RigidTransform3& a, const RigidTransform3& b) {
    return {a.rotation * b.rotation, a.rotation * b.translation + a.translation};
  }

  // x_a = T_a_b * x_b
  friend Vector3 operator*(const RigidTransform3& t, const Vector3& x) {
    return t.rotation * x + t.translation;
  }

  template <class Other>
  [[nodiscard]] RigidTransform3<Other> cast() const {
    return {rotation.template cast<Other>(), translation.template cast<Other>()};
  }
};

using RigidTransform3d = RigidTransform3<double>;

}  // namespace livod

namespace livod::se3 {

template <class Scalar>
using Vector6 = Eigen::Matrix<Scalar, 6, 1>;
template <class Scalar>
using Matrix4 = Eigen::Matrix<Scalar, 4, 4>;
template <class Scalar>
using Matrix6 = Eigen::Matrix<Scalar, 6, 6>;

// ξ = [φ; ρ] -> the 4x4 twist matrix [[hat(φ), ρ], [0, 0]].
template <class Derived>
Matrix4<typename Derived::Scalar> hat(const Eigen::MatrixBase<Derived>& xi) {
  static_assert(Derived::RowsAtCompileTime == 6 && Derived::ColsAtCompileTime == 1,
                "expected a 6-vector [φ; ρ]");
  using Scalar = typename Derived::Scalar;
  Matrix4<Scalar> m = Matrix4<Scalar>::Zero();
  m.template topLeftCorner<3, 3>() = so3::hat(xi.template head<3>());
  m.template topRightCorner<3, 1>() = xi.template tail<3>();
  return m;
}

template <class Derived>
Vector6<typename Derived::Scalar> vee(const Eigen::MatrixBase<Derived>& m) {
  static_assert(Derived::RowsAtCompileTime == 4 && Derived::ColsAtCompileTime == 4,
                "expected a 4x4 twist matrix");
  Vector6<typename Derived::Scalar> xi;
  xi << so3::vee(m.template topLeftCorner<3, 3>()), m.template topRightCorner<3, 1>();
  return xi;
}

// V(φ): the translation of Exp([φ; ρ]) is V(φ)·ρ. V is the left Jacobian of SO(3).
template <class Derived>
so3::Matrix3<typename Derived::Scalar> v_matrix(const Eigen::MatrixBase<Derived>& phi) {
  return so3::left_jacobian(phi);
}

template <class Derived>
so3::Matrix3<typename Derived::Scalar> v_matrix_inverse(const Eigen::MatrixBase<Derived>& phi) {
  return so3::left_jacobian_inverse(phi);
}

template <class Derived>
RigidTransform3<typename Derived::Scalar> exp(const Eigen::MatrixBase<Derived>& xi) {
  static_assert(Derived::RowsAtCompileTime == 6 && Derived::ColsAtCompileTime == 1,
                "expected a 6-vector [φ; ρ]");
  using Scalar = typename Derived::Scalar;
  const so3::Vector3<Scalar> phi = xi.template head<3>();
  const so3::Vector3<Scalar> rho = xi.template tail<3>();
  return {so3::exp(phi), v_matrix(phi) * rho};
}

template <class Scalar>
Vector6<Scalar> log(const RigidTransform3<Scalar>& t) {
  const so3::Vector3<Scalar> phi = so3::log(t.rotation);
  Vector6<Scalar> xi;
  xi << phi, v_matrix_inverse(phi) * t.translation;
  return xi;
}

// Ad_T with T·Exp(ξ)·T⁻¹ = Exp(Ad_T·ξ) for ξ = [φ; ρ]:
//   Ad_T = [[R, 0], [hat(p)·R, R]].
template <class Scalar>
Matrix6<Scalar> adjoint(const RigidTransform3<Scalar>& t) {
  Matrix6<Scalar> ad = Matrix6<Scalar>::Zero();
  ad.template topLeftCorner<3, 3>() = t.rotation;
  ad.template bottomLeftCorner<3, 3>() = so3::hat(t.translation) * t.rotation;
  ad.template bottomRightCorner<3, 3>() = t.rotation;
  return ad;
}

// T ⊞ ξ = T·Exp(ξ) (right perturbation on SE(3): ξ is expressed in the body frame of T).
template <class Scalar, class Derived>
RigidTransform3<Scalar> boxplus(const RigidTransform3<Scalar>& t,
                                const Eigen::MatrixBase<Derived>& xi) {
  static_assert(std::is_same_v<Scalar, typename Derived::Scalar>, "scalar types must match");
  return t * exp(xi);
}

// T1 ⊟ T0 = Log(T0⁻¹·T1), so that T0 ⊞ (T1 ⊟ T0) == T1.
template <class Scalar>
Vector6<Scalar> boxminus(const RigidTransform3<Scalar>& t1, const RigidTransform3<Scalar>& t0) {
  return log(t0.inverse() * t1);
}

// Constant-twist (screw) interpolation T0·Exp(s·Log(T0⁻¹T1)); s in [0, 1].
template <class Scalar>
RigidTransform3<Scalar> interpolate(const RigidTransform3<Scalar>& t0,
                                    const RigidTransform3<Scalar>& t1, Scalar s) {
  const Vector6<Scalar> xi = boxminus(t1, t0);
  return t0 * exp(Vector6<Scalar>(s * xi));
}

}  // namespace livod::se3

namespace livod::so3_r3 {

template <class Scalar>
using Vector6 = Eigen::Matrix<Scalar, 6, 1>;

// (R, p) ⊞ [δθ; δp] = (R·Exp(δθ), p + δp): the filter's pose perturbation.
template <class Scalar, class Derived>
RigidTransform3<Scalar> boxplus(const RigidTransform3<Scalar>& t,
                                const Eigen::MatrixBase<Derived>& delta) {
  static_assert(Derived::RowsAtCompileTime == 6 && Derived::ColsAtCompileTime == 1,
                "expected a 6-vector [δθ; δp]");
  static_assert(std::is_same_v<Scalar, typename Derived::Scalar>, "scalar types must match");
  return {so3::boxplus(t.rotation, delta.template head<3>()),
          t.translation + delta.template tail<3>()};
}

// (R1, p1) ⊟ (R0, p0) = [Log(R0ᵀR1); p1 − p0].
template <class Scalar>
Vector6<Scalar> boxminus(const RigidTransform3<Scalar>& t1, const RigidTransform3<Scalar>& t0) {
  Vector6<Scalar> d;
  d << so3::boxminus(t1.rotation, t0.rotation), t1.translation - t0.translation;
  return d;
}

// Rotation by slerp, translation linearly: what a trajectory sampled in time usually wants
// (the position does not follow a screw arc between samples).
template <class Scalar>
RigidTransform3<Scalar> interpolate(const RigidTransform3<Scalar>& t0,
                                    const RigidTransform3<Scalar>& t1, Scalar s) {
  return {so3::interpolate(t0.rotation, t1.rotation, s),
          (Scalar(1) - s) * t0.translation + s * t1.translation};
}

}  // namespace livod::so3_r3

// SO(3)/SE(3) helpers: every Jacobian against central finite differences, Exp/Log round trips
// over the whole angle range (tiny angles, moderate, near and at π), group properties, and
// the box operators of both pose conventions.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>
#include <unsupported/Eigen/MatrixFunctions>
#include <vector>

#include "core/se3.hpp"
#include "core/so3.hpp"

namespace livod {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

constexpr double kPi = std::numbers::pi;

// Rotation vectors with angles spread over [0, π]: the branches of every function (Taylor below
// ε^¼, closed form, near-π logarithm) are all visited.
std::vector<Vector3d> test_rotation_vectors(std::mt19937& rng) {
  const std::vector<double> angles = {0.0,  1e-12,      1e-9,       1e-6,       1e-4,
                                      2e-4, 1e-2,       0.3,        1.0,        2.0,
                                      2.5,  kPi - 1e-1, kPi - 1e-3, kPi - 1e-6, kPi - 1e-9};
  std::normal_distribution<double> normal;
  std::vector<Vector3d> out;
  for (double angle : angles) {
    for (int k = 0; k < 4; ++k) {
      Vector3d axis(normal(rng), normal(rng), normal(rng));
      axis.normalize();
      out.push_back(angle * axis);
    }
  }
  // Axis-aligned cases, where a near-π branch has to pick the right column.
  for (int i = 0; i < 3; ++i) {
    out.push_back((kPi - 1e-7) * Vector3d::Unit(i));
    out.push_back(-(kPi - 1e-7) * Vector3d::Unit(i));
  }
  return out;
}

// Central differences of f: R^n -> R^m at x.
template <int N, int M, class F>
Eigen::Matrix<double, M, N> numerical_jacobian(F f, const Eigen::Matrix<double, N, 1>& x,
                                               double h) {
  Eigen::Matrix<double, M, N> jac;
  for (int i = 0; i < N; ++i) {
    Eigen::Matrix<double, N, 1> dx = Eigen::Matrix<double, N, 1>::Zero();
    dx(i) = h;
    jac.col(i) = (f(x + dx) - f(x - dx)) / (2 * h);
  }
  return jac;
}

bool is_rotation(const Matrix3d& r, double tol) {
  return (r.transpose() * r - Matrix3d::Identity()).norm() < tol &&
         std::abs(r.determinant() - 1) < tol;
}

TEST(So3, HatIsCrossProductAndVeeInvertsIt) {
  const Vector3d a(0.3, -1.2, 2.5);
  const Vector3d b(-0.7, 0.4, 1.1);
  EXPECT_TRUE((so3::hat(a) * b).isApprox(a.cross(b), 1e-15));
  EXPECT_TRUE((so3::hat(a) + so3::hat(a).transpose()).isZero(0.0));
  EXPECT_EQ(so3::vee(so3::hat(a)), a);
}

TEST(So3, ExpMatchesAngleAxisAndIsARotation) {
  std::mt19937 rng(7);
  for (const Vector3d& phi : test_rotation_vectors(rng)) {
    const Matrix3d r = so3::exp(phi);
    EXPECT_TRUE(is_rotation(r, 1e-14)) << phi.transpose();
    const double angle = phi.norm();
    const Matrix3d expected =
        angle > 0 ? Eigen::AngleAxisd(angle, phi / angle).toRotationMatrix() : Matrix3d::Identity();
    EXPECT_LT((r - expected).norm(), 1e-14) << phi.transpose();
  }
}

TEST(So3, ExpSeriesBranchIsExactToRoundOff) {
  // Below 0.05 rad exp() uses a Taylor series instead of sin/cos: on both sides of the switch and
  // down to tiny angles it must agree with the angle-axis rotation to round-off.
  std::mt19937 rng(17);
  std::normal_distribution<double> g(0.0, 1.0);
  for (double angle : {1e-12, 1e-9, 1e-6, 1e-3, 0.01, 0.03, 0.0499999, 0.05, 0.0500001, 0.07}) {
    for (int k = 0; k < 20; ++k) {
      const Vector3d axis = Vector3d(g(rng), g(rng), g(rng)).normalized();
      const Matrix3d expected = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
      EXPECT_LT((so3::exp(Vector3d(angle * axis)) - expected).norm(), 4e-16) << angle;
    }
  }
}

TEST(So3, ExpMatchesMatrixExponentialOfHat) {
  std::mt19937 rng(8);
  for (const Vector3d& phi : test_rotation_vectors(rng)) {
    const Matrix3d expected = so3::hat(phi).exp();
    EXPECT_LT((so3::exp(phi) - expected).norm(), 1e-13) << phi.transpose();
  }
}

TEST(So3, LogInvertsExpOverTheWholeRange) {
  std::mt19937 rng(9);
  for (const Vector3d& phi : test_rotation_vectors(rng)) {
    const Vector3d back = so3::log(so3::exp(phi));
    // The error bound of Log near π is ε/(π − θ) for the generic formula; the near-π branch
    // keeps it at a few ε.
    EXPECT_LT((back - phi).norm(), 1e-12) << phi.transpose() << " -> " << back.transpose();
  }
}

TEST(So3, LogAtExactlyPiReturnsAValidRotationVector) {
  for (const Vector3d& axis :
       {Vector3d(1, 0, 0), Vector3d(0, 1, 0), Vector3d(0, 0, 1), Vector3d(1, 2, -3).normalized()}) {
    const Matrix3d r = Eigen::AngleAxisd(kPi, axis).toRotationMatrix();
    const Vector3d phi = so3::log(r);
    EXPECT_NEAR(phi.norm(), kPi, 1e-12);
    EXPECT_NEAR(std::abs(phi.normalized().dot(axis)), 1.0, 1e-12);
    EXPECT_LT((so3::exp(phi) - r).norm(), 1e-12);
  }
}

TEST(So3, LogOfTinyRotationKeepsRelativePrecision) {
  // A rotation of 1e-10 rad: 1 − cos θ underflows in acos-based logs, the atan2 form keeps it.
  const Vector3d phi(3e-11, -4e-11, 0.0);
  const Vector3d back = so3::log(so3::exp(phi));
  EXPECT_LT((back - phi).norm(), 1e-9 * phi.norm());
}

TEST(So3, RightJacobianMatchesFiniteDifferences) {
  // Exp(φ + δ) ≈ Exp(φ)·Exp(Jr(φ)·δ)  ⇒  Jr = d Log(Exp(φ)ᵀ·Exp(φ + δ)) / dδ.
  std::mt19937 rng(10);
  for (const Vector3d& phi : test_rotation_vectors(rng)) {
    const Matrix3d r0t = so3::exp(phi).transpose();
    const auto f = [&](const Vector3d& d) -> Vector3d { return so3::log(r0t * so3::exp(phi + d)); };
    const Matrix3d numeric = numerical_jacobian<3, 3>(f, Vector3d::Zero(), 1e-6);
    EXPECT_LT((so3::right_jacobian(phi) - numeric).norm(), 1e-8) << phi.transpose();
  }
}

TEST(So3, LeftJacobianMatchesFiniteDifferences) {
  // Exp(φ + δ) ≈ Exp(Jl(φ)·δ)·Exp(φ)  ⇒  Jl = d Log(Exp(φ + δ)·Exp(φ)ᵀ) / dδ.
  std::mt19937 rng(11);
  for (const Vector3d& phi : test_rotation_vectors(rng)) {
    const Matrix3d r0t = so3::exp(phi).transpose();
    const auto f = [&](const Vector3d& d) -> Vector3d { return so3::log(so3::exp(phi + d) * r0t); };
    const Matrix3d numeric = numerical_jacobian<3, 3>(f, Vector3d::Zero(), 1e-6);
    EXPECT_LT((so3::left_jacobian(phi) - numeric).norm(), 1e-8) << phi.transpose();
    EXPECT_LT((so3::left_jacobian(phi) - so3::right_jacobian(phi).transpose()).norm(), 1e-15);
  }
}

TEST(So3, InverseRightJacobianMatchesFiniteDifferencesOfLog) {
  // d Log(Exp(φ)·Exp(δ)) / dδ = Jr⁻¹(φ). Angles up to π − 1e-3 so that ±h never wraps past π.
  std::mt19937 rng(12);
  for (const Vector3d& phi : test_rotation_vectors(rng)) {
    if (phi.norm() > kPi - 1e-3 + 1e-12) continue;
    const Matrix3d r0 = so3::exp(phi);
    const auto f = [&](const Vector3d& d) -> Vector3d { return so3::log(r0 * so3::exp(d)); };
    const Matrix3d numeric = numerical_jacobian<3, 3>(f, Vector3d::Zero(), 1e-6);
    EXPECT_LT((so3::right_jacobian_inverse(phi) - numeric).norm(), 1e-7) << phi.transpose();
  }
}

TEST(So3, InverseLeftJacobianMatchesFiniteDifferencesOfLog) {
  // d Log(Exp(δ)·Exp(φ)) / dδ = Jl⁻¹(φ).
  std::mt19937 rng(13);
  for (const Vector3d& phi : test_rotation_vectors(rng)) {
    if (phi.norm() > kPi - 1e-3 + 1e-12) continue;
    const Matrix3d r0 = so3::exp(phi);
    const auto f = [&](const Vector3d& d) -> Vector3d { return so3::log(so3::exp(d) * r0); };
    const Matrix3d numeric = numerical_jacobian<3, 3>(f, Vector3d::Zero(), 1e-6);
    EXPECT_LT((so3::left_jacobian_inverse(phi) - numeric).norm(), 1e-7) << phi.transpose();
  }
}

TEST(So3, JacobianInversesAreInversesUpToPi) {
  std::mt19937 rng(14);
  for (const Vector3d& phi : test_rotation_vectors(rng)) {
    EXPECT_LT(
        (so3::right_jacobian(phi) * so3::right_jacobian_inverse(phi) - Matrix3d::Identity()).norm(),
        1e-12)
        << phi.transpose();
    EXPECT_LT(
        (so3::left_jacobian(phi) * so3::left_jacobian_inverse(phi) - Matrix3d::Identity()).norm(),
        1e-12)
        << phi.transpose();
  }
  // Exactly π: Jr⁻¹ is finite there (its pole is at 2π).
  const Vector3d phi_pi = kPi * Vector3d(2, -1, 2).normalized();
  EXPECT_TRUE(so3::right_jacobian_inverse(phi_pi).allFinite());
  EXPECT_LT(
      (so3::right_jacobian(phi_pi) * so3::right_jacobian_inverse(phi_pi) - Matrix3d::Identity())
          .norm(),
      1e-12);
}

TEST(So3, BoxOperatorsUseTheRightPerturbation) {
  const Matrix3d r = so3::exp(Vector3d(0.4, -1.0, 2.2));
  const Vector3d delta(0.01, 0.02, -0.03);
  // R ⊞ δ = R·Exp(δ), not Exp(δ)·R.
  EXPECT_LT((so3::boxplus(r, delta) - r * so3::exp(delta)).norm(), 1e-15);
  EXPECT_GT((so3::boxplus(r, delta) - so3::exp(delta) * r).norm(), 1e-3);
  EXPECT_LT((so3::boxminus(so3::boxplus(r, delta), r) - delta).norm(), 1e-15);
  const Matrix3d r1 = so3::exp(Vector3d(-2.0, 0.5, 1.0));
  EXPECT_LT((so3::boxplus(r, so3::boxminus(r1, r)) - r1).norm(), 1e-14);
}

TEST(So3, BoxminusJacobiansAreTheInverseJacobians) {
  // d(R1 ⊟ R0)/dδ1 at R1 ⊞ δ1 is Jr⁻¹(R1 ⊟ R0): the identity the filter's update relies on.
  const Matrix3d r0 = so3::exp(Vector3d(0.2, 0.9, -0.4));
  const Matrix3d r1 = so3::exp(Vector3d(-1.5, 0.3, 1.7));
  const Vector3d phi = so3::boxminus(r1, r0);
  const auto f = [&](const Vector3d& d) -> Vector3d {
    return so3::boxminus(so3::boxplus(r1, d), r0);
  };
  const Matrix3d numeric = numerical_jacobian<3, 3>(f, Vector3d::Zero(), 1e-6);
  EXPECT_LT((numeric - so3::right_jacobian_inverse(phi)).norm(), 1e-8);
}

TEST(So3, InterpolationFollowsTheGeodesic) {
  const Matrix3d r0 = so3::exp(Vector3d(0.1, 0.2, 0.3));
  const Matrix3d r1 = so3::exp(Vector3d(1.0, -0.5, 2.0));
  EXPECT_LT((so3::interpolate(r0, r1, 0.0) - r0).norm(), 1e-15);
  EXPECT_LT((so3::interpolate(r0, r1, 1.0) - r1).norm(), 1e-14);
  const double total = so3::angle(r0.transpose() * r1);
  const Matrix3d mid = so3::interpolate(r0, r1, 0.25);
  EXPECT_NEAR(so3::angle(r0.transpose() * mid), 0.25 * total, 1e-14);
  EXPECT_NEAR(so3::angle(mid.transpose() * r1), 0.75 * total, 1e-14);
  // Same as quaternion slerp.
  const Eigen::Quaterniond q = Eigen::Quaterniond(r0).slerp(0.25, Eigen::Quaterniond(r1));
  EXPECT_LT((q.toRotationMatrix() - mid).norm(), 1e-14);
}

TEST(So3, OrthonormalizeProjectsOntoSO3) {
  Matrix3d m = so3::exp(Vector3d(0.3, -0.2, 0.9));
  const Matrix3d truth = m;
  m(0, 1) += 1e-6;
  m(2, 2) -= 2e-6;
  const Matrix3d r = so3::orthonormalize(m);
  EXPECT_TRUE(is_rotation(r, 1e-14));
  EXPECT_LT((r - truth).norm(), 3e-6);
}

TEST(So3, FloatInstantiationWorks) {
  const Eigen::Vector3f phi(0.3f, -0.2f, 0.5f);
  const Eigen::Matrix3f r = so3::exp(phi);
  EXPECT_LT((so3::log(r) - phi).norm(), 1e-6f);
  EXPECT_LT(
      (so3::right_jacobian(phi) * so3::right_jacobian_inverse(phi) - Eigen::Matrix3f::Identity())
          .norm(),
      1e-6f);
}

// ---------------------------------------------------------------------------------------------

std::vector<Vector6d> test_twists(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  std::vector<Vector6d> out;
  for (const Vector3d& phi : test_rotation_vectors(rng)) {
    Vector6d xi;
    xi << phi, Vector3d(normal(rng), normal(rng), normal(rng)) * 3.0;
    out.push_back(xi);
  }
  return out;
}

RigidTransform3d random_transform(std::mt19937& rng) {
  std::uniform_real_distribution<double> uniform(-2.0, 2.0);
  const Vector3d phi(uniform(rng), uniform(rng), uniform(rng));
  return {so3::exp(phi), Vector3d(uniform(rng), uniform(rng), uniform(rng)) * 5.0};
}

TEST(Se3, ExpMatchesMatrixExponentialOfTwist) {
  // Independent check of the V matrix: the 4x4 matrix exponential of the twist.
  std::mt19937 rng(20);
  for (const Vector6d& xi : test_twists(rng)) {
    const Eigen::Matrix4d expected = se3::hat(xi).exp();
    EXPECT_LT((se3::exp(xi).matrix() - expected).norm(), 1e-12) << xi.transpose();
  }
}

TEST(Se3, LogInvertsExp) {
  std::mt19937 rng(21);
  for (const Vector6d& xi : test_twists(rng)) {
    const Vector6d back = se3::log(se3::exp(xi));
    // V⁻¹ grows like 1/(π − θ)² in the direction orthogonal to the axis near π, so the
    // translation part is looser there.
    const double tol = xi.head<3>().norm() > kPi - 1e-2 ? 1e-6 : 1e-12;
    EXPECT_LT((back - xi).norm(), tol * std::max(1.0, xi.norm())) << xi.transpose();
    EXPECT_EQ(se3::vee(se3::hat(xi)), xi);
  }
}

TEST(Se3, GroupProperties) {
  std::mt19937 rng(22);
  for (int i = 0; i < 50; ++i) {
    const RigidTransform3d a = random_transform(rng);
    const RigidTransform3d b = random_transform(rng);
    const RigidTransform3d c = random_transform(rng);
    const Vector3d x(0.5, -1.5, 2.0);
    EXPECT_LT((((a * b) * c).matrix() - (a * (b * c)).matrix()).norm(), 1e-12);
    EXPECT_LT(((a * a.inverse()).matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-14);
    EXPECT_LT(((a * b) * x - a * (b * x)).norm(), 1e-13);
    EXPECT_LT(((a * b).matrix() - a.matrix() * b.matrix()).norm(), 1e-13);
    const Vector6d xi = se3::log(a);
    EXPECT_LT((se3::exp(Vector6d(-xi)).matrix() - a.inverse().matrix()).norm(), 1e-12);
    // One-parameter subgroup: Exp(sξ)·Exp(tξ) = Exp((s + t)ξ).
    EXPECT_LT(((se3::exp(Vector6d(0.3 * xi)) * se3::exp(Vector6d(0.5 * xi))).matrix() -
               se3::exp(Vector6d(0.8 * xi)).matrix())
                  .norm(),
              1e-12);
  }
}

TEST(Se3, AdjointMovesATwistAcrossFrames) {
  std::mt19937 rng(23);
  for (int i = 0; i < 20; ++i) {
    const RigidTransform3d t = random_transform(rng);
    Vector6d xi;
    xi << 0.3, -0.1, 0.2, 1.0, -2.0, 0.5;
    const RigidTransform3d lhs = t * se3::exp(xi) * t.inverse();
    const RigidTransform3d rhs = se3::exp(Vector6d(se3::adjoint(t) * xi));
    EXPECT_LT((lhs.matrix() - rhs.matrix()).norm(), 1e-12);
  }
}

TEST(Se3, BoxOperatorsRoundTripAndActInTheBodyFrame) {
  std::mt19937 rng(24);
  for (int i = 0; i < 20; ++i) {
    const RigidTransform3d t0 = random_transform(rng);
    const RigidTransform3d t1 = random_transform(rng);
    const Vector6d d = se3::boxminus(t1, t0);
    EXPECT_LT((se3::boxplus(t0, d).matrix() - t1.matrix()).norm(), 1e-11);
    Vector6d small;
    small << 1e-3, -2e-3, 5e-4, 0.01, 0.02, -0.03;
    EXPECT_LT((se3::boxminus(se3::boxplus(t0, small), t0) - small).norm(), 1e-14);
    // A pure body-frame translation moves the origin along the body axes: p + R·ρ.
    Vector6d forward;
    forward << 0, 0, 0, 1.0, 0, 0;
    EXPECT_LT(
        (se3::boxplus(t0, forward).translation - (t0.translation + t0.rotation.col(0))).norm(),
        1e-14);
  }
}

TEST(Se3, InterpolationIsAScrewMotion) {
  std::mt19937 rng(25);
  const RigidTransform3d t0 = random_transform(rng);
  const RigidTransform3d t1 = random_transform(rng);
  EXPECT_LT((se3::interpolate(t0, t1, 0.0).matrix() - t0.matrix()).norm(), 1e-14);
  EXPECT_LT((se3::interpolate(t0, t1, 1.0).matrix() - t1.matrix()).norm(), 1e-11);
  // Half-way twice is the whole way: the midpoint's relative motion composes with itself.
  const RigidTransform3d mid = se3::interpolate(t0, t1, 0.5);
  const RigidTransform3d half_step = t0.inverse() * mid;
  EXPECT_LT(((t0 * half_step * half_step).matrix() - t1.matrix()).norm(), 1e-11);
  // Pure translation interpolates linearly.
  const RigidTransform3d a(Matrix3d::Identity(), Vector3d(1, 2, 3));
  const RigidTransform3d b(Matrix3d::Identity(), Vector3d(3, 2, -1));
  EXPECT_LT((se3::interpolate(a, b, 0.25).translation - Vector3d(1.5, 2, 2)).norm(), 1e-15);
}

TEST(So3R3, BoxOperatorsPerturbRotationOnTheRightAndTranslationInTheWorld) {
  std::mt19937 rng(30);
  for (int i = 0; i < 20; ++i) {
    const RigidTransform3d t = random_transform(rng);
    Vector6d d;
    d << 0.02, -0.01, 0.03, 0.5, -0.2, 0.1;
    const RigidTransform3d moved = so3_r3::boxplus(t, d);
    EXPECT_LT((moved.rotation - t.rotation * so3::exp(Vector3d(d.head<3>()))).norm(), 1e-15);
    EXPECT_LT((moved.translation - (t.translation + d.tail<3>())).norm(), 1e-15);
    EXPECT_LT((so3_r3::boxminus(moved, t) - d).norm(), 1e-14);
    const RigidTransform3d other = random_transform(rng);
    EXPECT_LT((so3_r3::boxplus(t, so3_r3::boxminus(other, t)).matrix() - other.matrix()).norm(),
              1e-12);
  }
}

TEST(So3R3, BoxminusJacobianIsBlockDiagonal) {
  // d((T ⊞ δ) ⊟ T0)/dδ = diag(Jr⁻¹(φ), I): the filter's measurement Jacobian for a pose prior.
  std::mt19937 rng(31);
  const RigidTransform3d t0 = random_transform(rng);
  const RigidTransform3d t = random_transform(rng);
  const Vector6d e = so3_r3::boxminus(t, t0);
  const auto f = [&](const Vector6d& d) -> Vector6d {
    return so3_r3::boxminus(so3_r3::boxplus(t, d), t0);
  };
  const Matrix6d numeric = numerical_jacobian<6, 6>(f, Vector6d::Zero(), 1e-6);
  Matrix6d expected = Matrix6d::Identity();
  expected.topLeftCorner<3, 3>() = so3::right_jacobian_inverse(Vector3d(e.head<3>()));
  EXPECT_LT((numeric - expected).norm(), 1e-8);
}

TEST(So3R3, InterpolationSlerpsRotationAndLerpsTranslation) {
  std::mt19937 rng(32);
  const RigidTransform3d t0 = random_transform(rng);
  const RigidTransform3d t1 = random_transform(rng);
  const RigidTransform3d mid = so3_r3::interpolate(t0, t1, 0.3);
  EXPECT_LT((mid.translation - (0.7 * t0.translation + 0.3 * t1.translation)).norm(), 1e-14);
  EXPECT_LT((mid.rotation - so3::interpolate(t0.rotation, t1.rotation, 0.3)).norm(), 1e-15);
  EXPECT_LT((so3_r3::interpolate(t0, t1, 1.0).matrix() - t1.matrix()).norm(), 1e-13);
}

}  // namespace
}  // namespace livod

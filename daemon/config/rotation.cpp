#include "daemon/config/rotation.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "core/units.hpp"

namespace livod::daemon {

namespace {

std::string number(double v) {
  std::ostringstream out;
  out.precision(6);
  out << v;
  return out.str();
}

}  // namespace

Eigen::Matrix3d rotation_from_rpy_deg(double roll_deg, double pitch_deg, double yaw_deg) {
  const Eigen::AngleAxisd roll(roll_deg * kDegToRad, Eigen::Vector3d::UnitX());
  const Eigen::AngleAxisd pitch(pitch_deg * kDegToRad, Eigen::Vector3d::UnitY());
  const Eigen::AngleAxisd yaw(yaw_deg * kDegToRad, Eigen::Vector3d::UnitZ());
  return (yaw * pitch * roll).toRotationMatrix();
}

Eigen::Vector3d rpy_deg_from_rotation(const Eigen::Matrix3d& R) {
  // R = Rz(y) Ry(p) Rx(r): R(2,0) = -sin p, R(2,1) = cos p sin r, R(2,2) = cos p cos r,
  // R(1,0) = sin y cos p, R(0,0) = cos y cos p.
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  double roll = 0.0;
  double yaw = 0.0;
  if (std::abs(std::cos(pitch)) > 1e-9) {
    roll = std::atan2(R(2, 1), R(2, 2));
    yaw = std::atan2(R(1, 0), R(0, 0));
  } else {
    // Gimbal lock: only roll - yaw (or roll + yaw) is defined; put it all in yaw.
    yaw = std::atan2(-R(0, 1), R(1, 1));
  }
  return Eigen::Vector3d(roll, pitch, yaw) / kDegToRad;
}

RotationResult rotation_from_quaternion(double w, double x, double y, double z) {
  RotationResult result;
  const Eigen::Quaterniond q(w, x, y, z);
  const double norm = q.norm();
  if (!std::isfinite(norm) || std::abs(norm - 1.0) > kRotationTolerance) {
    result.message = "quaternion norm is " + number(norm) + ", not 1 (tolerance " +
                     number(kRotationTolerance) + ")";
    return result;
  }
  result.ok = true;
  result.rotation = q.normalized().toRotationMatrix();
  return result;
}

RotationResult rotation_from_matrix(const Eigen::Matrix3d& m) {
  RotationResult result;
  if (!m.allFinite()) {
    result.message = "matrix has non-finite entries";
    return result;
  }
  const double orthonormality_error =
      (m.transpose() * m - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orthonormality_error > kRotationTolerance) {
    result.message =
        "matrix is not orthonormal (max |R^T R - I| = " + number(orthonormality_error) +
        ", tolerance " + number(kRotationTolerance) + ")";
    return result;
  }
  if (m.determinant() < 0.0) {
    result.message = "matrix is a reflection (determinant -1), not a rotation";
    return result;
  }
  // Snap onto SO(3): the closest rotation in the Frobenius norm is U V^T.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  result.ok = true;
  result.rotation = svd.matrixU() * svd.matrixV().transpose();
  return result;
}

}  // namespace livod::daemon

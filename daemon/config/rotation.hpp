#pragma once
// The three ways a rotation may be written in the configuration, and their checks.
//
// rpy_deg [roll, pitch, yaw] follows the ROS/URDF convention: fixed axes X, then Y, then Z,
// i.e. R = Rz(yaw) * Ry(pitch) * Rx(roll) (equivalently intrinsic Z-Y'-X''), angles in degrees.
// Quaternions and matrices are accepted when they are within kRotationTolerance of a rotation
// (rounding in a pasted calibration) and are then snapped onto SO(3).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

namespace livod::daemon {

// Maximum |q| - 1 for a quaternion and max |R^T R - I| entry for a matrix.
constexpr double kRotationTolerance = 1e-3;

Eigen::Matrix3d rotation_from_rpy_deg(double roll_deg, double pitch_deg, double yaw_deg);
// Inverse of rotation_from_rpy_deg (pitch in [-90, 90]); used to print extrinsics.
Eigen::Vector3d rpy_deg_from_rotation(const Eigen::Matrix3d& R);

struct RotationResult {
  bool ok = false;
  std::string message;  // why it is not a rotation, when !ok
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
};

RotationResult rotation_from_quaternion(double w, double x, double y, double z);
RotationResult rotation_from_matrix(const Eigen::Matrix3d& m);

}  // namespace livod::daemon

#pragma once
// A world point seen from the filter state: its pixel and the pixel's Jacobian with respect to
// the pose error state, through the camera's own model (core/camera_model: pinhole +
// radial-tangential or equidistant, distortion included). FAST-LIVO2 uses the pinhole Jacobian
// fx/z for every model (defect 9), which overestimates a fisheye's by 1.8x at 40 deg.
//
// Frames: the camera is rigidly mounted at T_imu_cam (x_imu = T_imu_cam x_cam). With the right
// perturbation R_world_imu Exp(dtheta) and p_world_imu + dp of filter/state.hpp,
//   p_imu = R_wi^T (p_w - p_wi)        d p_imu / d dtheta = [p_imu]x,  d p_imu / d dp = -R_wi^T
//   p_cam = R_ci p_imu + t_ci          d pixel / d (dtheta, dp) = J_model R_ci [[p_imu]x, -R_wi^T]

#include <Eigen/Geometry>
#include <optional>

#include "core/camera_model.hpp"
#include "estimator/filter/state.hpp"

namespace livod::estimator::vio {

// The camera's pose in the IMU (body) frame, kept in both directions.
struct CameraExtrinsic {
  Eigen::Matrix3d R_imu_cam = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t_imu_cam = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R_cam_imu = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t_cam_imu = Eigen::Vector3d::Zero();

  static CameraExtrinsic from(const Eigen::Isometry3d& T_imu_cam) {
    CameraExtrinsic e;
    e.R_imu_cam = T_imu_cam.linear();
    e.t_imu_cam = T_imu_cam.translation();
    e.R_cam_imu = e.R_imu_cam.transpose();
    e.t_cam_imu = -e.R_cam_imu * e.t_imu_cam;
    return e;
  }

  // The camera's pose in the world for IMU pose x.
  [[nodiscard]] Eigen::Isometry3d T_world_cam(const State& x) const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = x.R_world_imu * R_imu_cam;
    T.translation() = x.R_world_imu * t_imu_cam + x.p_world_imu;
    return T;
  }
};

using PoseJacobian = Eigen::Matrix<double, 2, 6>;  // d pixel / d (dtheta, dp)

// Pixel (level 0) of p_world seen from state x; nullopt when behind the camera. J (optional):
// d pixel / d (dtheta, dp). p_cam (optional): the point in the camera frame.
std::optional<Eigen::Vector2d> project_from_state(const CameraModel& camera,
                                                  const CameraExtrinsic& extrinsic, const State& x,
                                                  const Eigen::Vector3d& p_world,
                                                  PoseJacobian* J = nullptr,
                                                  Eigen::Vector3d* p_cam = nullptr);

}  // namespace livod::estimator::vio

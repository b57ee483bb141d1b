#include "estimator/vio/camera_projection.hpp"

#include "core/so3.hpp"

namespace livod::estimator::vio {

std::optional<Eigen::Vector2d> project_from_state(const CameraModel& camera,
                                                  const CameraExtrinsic& extrinsic, const State& x,
                                                  const Eigen::Vector3d& p_world, PoseJacobian* J,
                                                  Eigen::Vector3d* p_cam_out) {
  const Eigen::Vector3d p_imu = x.R_world_imu.transpose() * (p_world - x.p_world_imu);
  const Eigen::Vector3d p_cam = extrinsic.R_cam_imu * p_imu + extrinsic.t_cam_imu;
  if (p_cam_out != nullptr) *p_cam_out = p_cam;
  Eigen::Matrix<double, 2, 3> J_model;
  const auto px = camera.project(p_cam, J != nullptr ? &J_model : nullptr);
  if (!px) return std::nullopt;
  if (J != nullptr) {
    const Eigen::Matrix<double, 2, 3> J_imu = J_model * extrinsic.R_cam_imu;
    J->leftCols<3>() = J_imu * so3::hat(p_imu);
    J->rightCols<3>() = -J_imu * x.R_world_imu.transpose();
  }
  return px;
}

}  // namespace livod::estimator::vio

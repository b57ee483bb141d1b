#pragma once
// Backward undistortion (fast-livo2-notes.md 1.2): every LiDAR point, measured at its own time,
// is moved into the LiDAR frame at one reference time (the scan end / update time) using the IMU
// poses propagated through the scan. Between IMU samples the motion is extrapolated with the
// sample's constant angular rate and world acceleration, as the propagation itself assumes.

#include <Eigen/Geometry>
#include <vector>

#include "core/measurement.hpp"
#include "core/time.hpp"
#include "estimator/task_runner.hpp"

namespace livod::estimator {

struct ImuPose {
  MappedTime t;
  Eigen::Matrix3d R_world_imu = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_world_imu = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d omega_imu = Eigen::Vector3d::Zero();  // bias-corrected rate used after t
  Eigen::Vector3d acc_world = Eigen::Vector3d::Zero();  // R a + g used after t
};

class ImuPoseTrack {
 public:
  void clear() { poses_.clear(); }
  // Poses must be pushed in time order.
  void push(const ImuPose& pose) { poses_.push_back(pose); }
  [[nodiscard]] bool empty() const { return poses_.empty(); }
  [[nodiscard]] const std::vector<ImuPose>& poses() const { return poses_; }

  // The IMU pose at t, extrapolated from the last pose at or before t (the first pose for
  // earlier times).
  [[nodiscard]] Eigen::Isometry3d T_world_imu(MappedTime t) const;

 private:
  std::vector<ImuPose> poses_;
};

// p_lidar(t_ref) = T_lidar_imu * T_world_imu(t_ref)^-1 * T_world_imu(t_i) * T_imu_lidar * p_i
// for the scan points `indices`; results in the same order, independent of `runner` (nullptr: on
// the caller's thread).
void undistort_points(const ImuPoseTrack& track, const Eigen::Isometry3d& T_imu_lidar,
                      MappedTime t_ref, const LidarScan& scan,
                      const std::vector<std::uint32_t>& indices, std::vector<Eigen::Vector3d>& out,
                      TaskRunner* runner = nullptr);

}  // namespace livod::estimator

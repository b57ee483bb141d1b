#include "estimator/imu/undistortion.hpp"

#include <algorithm>

#include "core/so3.hpp"

namespace livod::estimator {

Eigen::Isometry3d ImuPoseTrack::T_world_imu(MappedTime t) const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (poses_.empty()) return T;
  auto it = std::upper_bound(poses_.begin(), poses_.end(), t,
                             [](MappedTime a, const ImuPose& p) { return a < p.t; });
  const ImuPose& p = it == poses_.begin() ? poses_.front() : *(it - 1);
  const double dt = to_seconds(t - p.t);
  T.linear() = p.R_world_imu * so3::exp(p.omega_imu * dt);
  T.translation() = p.p_world_imu + p.v_world * dt + 0.5 * p.acc_world * dt * dt;
  return T;
}

void undistort_points(const ImuPoseTrack& track, const Eigen::Isometry3d& T_imu_lidar,
                      MappedTime t_ref, const LidarScan& scan,
                      const std::vector<std::uint32_t>& indices,
                      std::vector<Eigen::Vector3d>& out) {
  out.resize(indices.size());
  const Eigen::Isometry3d T_lidar_world_ref = (track.T_world_imu(t_ref) * T_imu_lidar).inverse();
  // Points in a scan are mostly time-ordered; cache the pose of the last time seen.
  std::int64_t cached_t = std::numeric_limits<std::int64_t>::min();
  Eigen::Isometry3d T_ref_lidar_i = Eigen::Isometry3d::Identity();
  for (std::size_t k = 0; k < indices.size(); ++k) {
    const std::uint32_t i = indices[k];
    const MappedTime t = scan.point_time(i);
    if (t.ns != cached_t) {
      T_ref_lidar_i = T_lidar_world_ref * track.T_world_imu(t) * T_imu_lidar;
      cached_t = t.ns;
    }
    out[k] = T_ref_lidar_i * scan.point(i).cast<double>();
  }
}

}  // namespace livod::estimator

#include "estimator/imu/undistortion.hpp"

#include <algorithm>
#include <limits>

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
                      const std::vector<std::uint32_t>& indices, std::vector<Eigen::Vector3d>& out,
                      TaskRunner* runner) {
  out.resize(indices.size());
  const Eigen::Isometry3d T_lidar_world_ref = (track.T_world_imu(t_ref) * T_imu_lidar).inverse();
  const Eigen::Matrix3d A = T_lidar_world_ref.linear();
  const Eigen::Vector3d a = T_lidar_world_ref.translation();
  const Eigen::Matrix3d& B = T_imu_lidar.linear();
  const Eigen::Vector3d& b = T_imu_lidar.translation();
  const auto& poses = track.poses();
  if (poses.empty()) {
    for (std::size_t k = 0; k < indices.size(); ++k) {
      out[k] = T_lidar_world_ref * (T_imu_lidar * scan.point(indices[k]).cast<double>());
    }
    return;
  }
  // p_ref = A (R_k Exp(w_k dt) (B p + b) + p_k + v_k dt + acc_k dt^2 / 2) + a, with pose k the
  // last at or before the point's time (T_world_imu()'s extrapolation), folded per IMU segment
  // (M, c, ...) and per distinct point time (G, g): a point then costs two matrix-vector
  // products.
  // Each range caches its own segment and time: the result of a point does not depend on how the
  // points are split between threads.
  const auto undistort_range = [&](std::size_t begin, std::size_t end) {
    std::size_t seg = 0;
    std::size_t cached_seg = poses.size();  // none
    Eigen::Matrix3d M = Eigen::Matrix3d::Identity();
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    Eigen::Vector3d Av = Eigen::Vector3d::Zero();
    Eigen::Vector3d Aa = Eigen::Vector3d::Zero();
    std::int64_t cached_t = std::numeric_limits<std::int64_t>::min();
    Eigen::Matrix3d G = Eigen::Matrix3d::Identity();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (std::size_t k = begin; k < end; ++k) {
      const std::uint32_t i = indices[k];
      const MappedTime t = scan.point_time(i);
      if (t.ns != cached_t) {
        // Segment of t: points are mostly time-ordered, so step forward; search otherwise.
        if (t < poses[seg].t) {
          const auto it = std::upper_bound(poses.begin(), poses.end(), t,
                                           [](MappedTime x, const ImuPose& p) { return x < p.t; });
          seg = it == poses.begin() ? 0 : static_cast<std::size_t>(it - poses.begin()) - 1;
        }
        while (seg + 1 < poses.size() && poses[seg + 1].t <= t) ++seg;
        const ImuPose& p = poses[seg];
        if (seg != cached_seg) {
          M = A * p.R_world_imu;
          c = A * p.p_world_imu + a;
          Av = A * p.v_world;
          Aa = 0.5 * (A * p.acc_world);
          cached_seg = seg;
        }
        const double dt = to_seconds(t - p.t);
        G = M * so3::exp(p.omega_imu * dt);
        g = c + Av * dt + Aa * (dt * dt);
        cached_t = t.ns;
      }
      out[k] = G * (B * scan.point(i).cast<double>() + b) + g;
    }
  };
  if (runner != nullptr) {
    parallel_for(*runner, indices.size(), 2048, undistort_range);
  } else {
    undistort_range(0, indices.size());
  }
}

}  // namespace livod::estimator

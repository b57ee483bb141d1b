#include "estimator/imu/undistortion.hpp"

#include <gtest/gtest.h>

#include <random>

#include "core/so3.hpp"

namespace livod::estimator {
namespace {

// Constant body rate and constant world acceleration: the track's extrapolation is exact, so
// undistortion must recover the static world points to numerical precision.
TEST(Undistortion, RecoversStaticPointsUnderConstantRateAndAcceleration) {
  const Eigen::Vector3d w(0.3, -0.2, 1.5);  // rad/s, body frame
  const Eigen::Vector3d v0(1.0, 0.5, 0.0);
  const Eigen::Vector3d acc(0.4, -0.3, 0.2);  // world
  auto truth = [&](double t) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = so3::exp(w * t);
    T.translation() = v0 * t + 0.5 * acc * t * t;
    return T;
  };
  ImuPoseTrack track;
  for (int k = 0; k <= 20; ++k) {  // 200 Hz over 0.1 s
    const double t = k * 0.005;
    ImuPose p;
    p.t = MappedTime::from_seconds(t);
    p.R_world_imu = truth(t).linear();
    p.p_world_imu = truth(t).translation();
    p.v_world = v0 + acc * t;
    p.omega_imu = w;
    p.acc_world = acc;
    track.push(p);
  }
  Eigen::Isometry3d T_imu_lidar = Eigen::Isometry3d::Identity();
  T_imu_lidar.linear() = so3::exp(Eigen::Vector3d(0.0, 0.0, 0.5));
  T_imu_lidar.translation() = Eigen::Vector3d(0.05, -0.02, 0.1);

  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  LidarScan scan;
  std::vector<Eigen::Vector3d> world;
  for (int i = 0; i < 1000; ++i) {
    const double t = i * 1e-4;  // 0 .. 0.1 s
    const Eigen::Vector3d p_world(u(rng), u(rng), u(rng));
    world.push_back(p_world);
    const Eigen::Vector3d p_lidar = (truth(t) * T_imu_lidar).inverse() * p_world;
    scan.push_back(static_cast<float>(p_lidar.x()), static_cast<float>(p_lidar.y()),
                   static_cast<float>(p_lidar.z()), 0.0F, 0, 0, static_cast<std::int32_t>(t * 1e9));
  }
  std::vector<std::uint32_t> idx(scan.size());
  for (std::uint32_t i = 0; i < idx.size(); ++i) idx[i] = i;
  std::vector<Eigen::Vector3d> out;
  const MappedTime t_end = MappedTime::from_seconds(0.1);
  undistort_points(track, T_imu_lidar, t_end, scan, idx, out);
  const Eigen::Isometry3d T_lidar_world_end = (truth(0.1) * T_imu_lidar).inverse();
  double worst = 0.0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    worst = std::max(worst, (out[i] - T_lidar_world_end * world[i]).norm());
  }
  EXPECT_LT(worst, 1e-5);  // float storage of the points is the only error
  // Without undistortion the error is large at these rates: the check is meaningful.
  double raw = 0.0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    raw = std::max(raw, (scan.point(i).cast<double>() - T_lidar_world_end * world[i]).norm());
  }
  EXPECT_GT(raw, 0.5);
}

}  // namespace
}  // namespace livod::estimator

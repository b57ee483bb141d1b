#include "estimator/lio/point_to_plane.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

namespace livod::estimator {
namespace {

TEST(PointToPlane, JacobianMatchesFiniteDifferences) {
  std::mt19937 rng(8);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Plane plane;
    plane.normal = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    plane.center = Eigen::Vector3d(g(rng), g(rng), g(rng)) * 5.0;
    plane.d = -plane.normal.dot(plane.center);
    State x;
    x.R_world_imu = so3::exp(Eigen::Vector3d(g(rng), g(rng), g(rng)));
    x.p_world_imu = Eigen::Vector3d(g(rng), g(rng), g(rng)) * 3.0;
    const Eigen::Vector3d p_imu = Eigen::Vector3d(g(rng), g(rng), g(rng)) * 10.0;
    const auto j = point_to_plane_jacobian(plane.normal, plane.d, p_imu, x);
    const double h = 1e-6;
    for (int c = 0; c < 6; ++c) {
      StateVector d = StateVector::Zero();
      d(c) = h;
      const double fd = (point_to_plane_jacobian(plane.normal, plane.d, p_imu, x.boxplus(d)).h -
                         point_to_plane_jacobian(plane.normal, plane.d, p_imu, x.boxplus(-d)).h) /
                        (2 * h);
      EXPECT_NEAR(j.H(c), fd, 1e-6 * (1.0 + std::abs(fd))) << "trial " << trial << " col " << c;
    }
  }
}

std::vector<CovPoint> floor_and_walls(std::mt19937& rng, int n) {
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  std::uniform_real_distribution<double> h(0.0, 3.0);
  std::vector<CovPoint> pts;
  for (int i = 0; i < n; ++i) {
    const int which = i % 3;
    CovPoint p;
    if (which == 0) p.p = Eigen::Vector3d(u(rng), u(rng), 0.0);
    if (which == 1) p.p = Eigen::Vector3d(4.0, u(rng), h(rng));
    if (which == 2) p.p = Eigen::Vector3d(u(rng), 4.0, h(rng));
    p.cov = Eigen::Matrix3d::Identity() * 1e-4;
    pts.push_back(p);
  }
  return pts;
}

// A scan of the same room seen from a displaced pose: the iterated update recovers the pose.
TEST(PointToPlane, UpdateRecoversAKnownPoseOffsetInAWellConstrainedRoom) {
  std::mt19937 rng(9);
  LioParams lio;
  VoxelMap map(lio, MapParams{});
  map.insert(floor_and_walls(rng, 60000));
  // Ceiling and the other two walls: a closed room constrains all six degrees of freedom.
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  std::uniform_real_distribution<double> hgt(0.0, 3.0);
  std::vector<CovPoint> more;
  for (int i = 0; i < 30000; ++i) {
    CovPoint p;
    p.cov = Eigen::Matrix3d::Identity() * 1e-4;
    p.p = (i % 2 == 0) ? Eigen::Vector3d(-4.0, u(rng), hgt(rng))
                       : Eigen::Vector3d(u(rng), -4.0, hgt(rng));
    more.push_back(p);
  }
  map.insert(more);

  State truth;
  truth.R_world_imu = so3::exp(Eigen::Vector3d(0.02, -0.01, 0.3));
  truth.p_world_imu = Eigen::Vector3d(0.5, -0.3, 1.2);
  const Eigen::Isometry3d T_imu_lidar = Eigen::Isometry3d::Identity();
  std::vector<ScanPoint> scan;
  for (int i = 0; i < 3000; ++i) {
    CovPoint w = floor_and_walls(rng, 3)[static_cast<std::size_t>(i % 3)];
    if (i % 5 == 0) w.p = Eigen::Vector3d(-4.0, u(rng), hgt(rng));
    if (i % 7 == 0) w.p = Eigen::Vector3d(u(rng), -4.0, hgt(rng));
    ScanPoint s;
    s.p_lidar = truth.R_world_imu.transpose() * (w.p - truth.p_world_imu);
    s.cov_lidar = Eigen::Matrix3d::Identity() * 1e-4;
    scan.push_back(s);
  }
  Belief b;
  b.x = truth;
  b.x.R_world_imu = truth.R_world_imu * so3::exp(Eigen::Vector3d(0.01, 0.01, -0.02));
  b.x.p_world_imu = truth.p_world_imu + Eigen::Vector3d(0.05, -0.04, 0.03);
  b.P = StateMatrix::Identity() * 0.01;
  PointToPlane p2p(map, T_imu_lidar, nullptr);
  IterationParams params;
  params.max_iterations = 10;
  const auto report = iterated_update(
      b, [&](const State& x, NormalEquations& eq) { return p2p.linearize(scan, x, eq, 50); },
      params);
  EXPECT_GT(report.measurements, 2000);
  EXPECT_LT((b.x.p_world_imu - truth.p_world_imu).norm(), 0.005);
  EXPECT_LT(so3::log(truth.R_world_imu.transpose() * b.x.R_world_imu).norm(), 0.002);
  const auto deg = assess_degeneracy(report.information, 0.01);
  EXPECT_FALSE(deg.degenerate) << deg.translation_eigenvalues.transpose();
}

// Several LiDARs: each point's incidence term uses its own LiDAR's bearing noise (set_lidar_noise)
// and ray. The rows of LiDAR 1's points in a two-LiDAR PointToPlane equal those of a one-LiDAR
// PointToPlane with LiDAR 1's extrinsic and noise, and differ from those with LiDAR 0's noise.
TEST(PointToPlane, EachLidarsPointsUseItsOwnNoise) {
  std::mt19937 rng(11);
  LioParams lio;
  VoxelMap map(lio, MapParams{});
  map.insert(floor_and_walls(rng, 60000));
  State x;
  x.R_world_imu = so3::exp(Eigen::Vector3d(0.01, -0.02, 0.2));
  x.p_world_imu = Eigen::Vector3d(0.3, -0.2, 1.1);
  Eigen::Isometry3d T0 = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T1 = Eigen::Isometry3d::Identity();
  T1.linear() = so3::exp(Eigen::Vector3d(0.0, 0.3, 3.0));
  T1.translation() = Eigen::Vector3d(-0.4, 0.1, 0.05);
  PointNoise fine;  // an Avia-like bearing noise
  fine.bearing_sigma_rad = 0.05 * M_PI / 180.0;
  PointNoise coarse = fine;  // a wider beam
  coarse.bearing_sigma_rad = 0.3 * M_PI / 180.0;
  std::vector<ScanPoint> scan;
  for (const CovPoint& w : floor_and_walls(rng, 2000)) {
    ScanPoint s;
    const Eigen::Vector3d p_imu = x.R_world_imu.transpose() * (w.p - x.p_world_imu);
    s.p_lidar = T1.inverse() * p_imu;
    s.cov_lidar = point_covariance(s.p_lidar, coarse);
    s.lidar = 1;
    scan.push_back(s);
  }
  PointToPlane pair(map, std::vector<Eigen::Isometry3d>{T0, T1}, nullptr, fine, true);
  pair.set_lidar_noise(1, coarse);
  std::vector<ScanPoint> alone_scan = scan;
  for (auto& s : alone_scan) s.lidar = 0;
  PointToPlane alone(map, T1, nullptr, coarse, true);
  PointToPlane wrong(map, T1, nullptr, fine, true);
  NormalEquations eq_pair, eq_alone, eq_wrong;
  ASSERT_TRUE(pair.linearize(scan, x, eq_pair, 50));
  ASSERT_TRUE(alone.linearize(alone_scan, x, eq_alone, 50));
  ASSERT_TRUE(wrong.linearize(alone_scan, x, eq_wrong, 50));
  EXPECT_EQ(eq_pair.measurements, eq_alone.measurements);
  const double scale = eq_alone.HtRinvH.norm();
  EXPECT_LT((eq_pair.HtRinvH - eq_alone.HtRinvH).norm(), 1e-9 * scale);
  EXPECT_NEAR(eq_pair.weighted_sq_residual, eq_alone.weighted_sq_residual,
              1e-9 * eq_alone.weighted_sq_residual + 1e-12);
  // The wider beam weighs the rows less: the test would see the wrong noise.
  EXPECT_GT((eq_wrong.HtRinvH - eq_alone.HtRinvH).norm(), 1e-3 * scale);
  EXPECT_THROW(pair.set_lidar_noise(2, coarse), std::invalid_argument);
}

// Several LiDARs: each LiDAR's rows may have their own association gate (set_lidar_gate; a
// matched-only LiDAR's default is 2 sigma). Points 0-4 sigma off their planes: LiDAR 1's rows at 2
// sigma in a pair are those of one LiDAR over a map whose sigma_num is 2, and fewer than at the
// map's 3.
TEST(PointToPlane, EachLidarsRowsUseItsOwnGate) {
  std::mt19937 rng(12);
  LioParams lio;  // sigma_num 3
  LioParams tight = lio;
  tight.sigma_num = 2.0;
  const std::vector<CovPoint> room = floor_and_walls(rng, 60000);
  VoxelMap map(lio, MapParams{});
  map.insert(room);
  VoxelMap tight_map(tight, MapParams{});
  tight_map.insert(room);
  State x;
  x.R_world_imu = so3::exp(Eigen::Vector3d(0.01, -0.02, 0.2));
  x.p_world_imu = Eigen::Vector3d(0.3, -0.2, 1.1);
  Eigen::Isometry3d T1 = Eigen::Isometry3d::Identity();
  T1.linear() = so3::exp(Eigen::Vector3d(0.0, 0.3, 3.0));
  T1.translation() = Eigen::Vector3d(-0.4, 0.1, 0.05);
  std::uniform_real_distribution<double> off(0.0, 0.04);  // 0-4 sigma of 1 cm
  std::vector<ScanPoint> scan;
  int i = 0;
  for (CovPoint w : floor_and_walls(rng, 3000)) {
    const int which = i++ % 3;  // floor, wall x = 4, wall y = 4 (floor_and_walls' order)
    w.p[which == 0 ? 2 : which == 1 ? 0 : 1] += which == 0 ? off(rng) : -off(rng);
    ScanPoint sp;
    const Eigen::Vector3d p_imu = x.R_world_imu.transpose() * (w.p - x.p_world_imu);
    sp.p_lidar = T1.inverse() * p_imu;
    sp.cov_lidar = Eigen::Matrix3d::Identity() * 1e-4;
    sp.lidar = 1;
    scan.push_back(sp);
  }
  std::vector<ScanPoint> alone_scan = scan;
  for (auto& sp : alone_scan) sp.lidar = 0;
  const std::vector<Eigen::Isometry3d> extrinsics{Eigen::Isometry3d::Identity(), T1};
  PointToPlane gated(map, extrinsics, nullptr);
  gated.set_lidar_gate(1, 2.0);
  PointToPlane ungated(map, extrinsics, nullptr);
  PointToPlane alone_tight(tight_map, T1, nullptr);
  NormalEquations eq_gated, eq_ungated, eq_alone;
  ASSERT_TRUE(gated.linearize(scan, x, eq_gated, 50));
  ASSERT_TRUE(ungated.linearize(scan, x, eq_ungated, 50));
  ASSERT_TRUE(alone_tight.linearize(alone_scan, x, eq_alone, 50));
  EXPECT_EQ(eq_gated.measurements, eq_alone.measurements);
  EXPECT_LT((eq_gated.HtRinvH - eq_alone.HtRinvH).norm(), 1e-9 * eq_alone.HtRinvH.norm());
  // About a quarter of the points lie 2-3 sigma off: the 3-sigma gate keeps them.
  EXPECT_GT(eq_ungated.measurements, eq_gated.measurements + 400);
  EXPECT_THROW(gated.set_lidar_gate(2, 2.0), std::invalid_argument);
  EXPECT_THROW(gated.set_lidar_gate(1, 0.0), std::invalid_argument);
}

TEST(PointToPlane, DegeneracyFlagsACorridor) {
  // Information from two parallel walls and a floor: nothing constrains x.
  StateMatrix info = StateMatrix::Zero();
  const std::vector<Eigen::Vector3d> normals = {{0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  for (const auto& n : normals) {
    Eigen::Matrix<double, 1, 6> H;
    H << Eigen::RowVector3d(0.1, 0.2, 0.0), n.transpose();
    info.block<6, 6>(0, 0) += 1000.0 * H.transpose() * H;
  }
  const auto deg = assess_degeneracy(info, 0.01);
  EXPECT_TRUE(deg.degenerate);
  EXPECT_GT(std::abs(deg.weakest_translation.x()), 0.99);
}

}  // namespace
}  // namespace livod::estimator

// XYZ projection: the factored LUT against a direct double-precision evaluation of the reference
// formula (sensor-protocols.md §3.6), analytic properties, and plausibility on a real drive
// (OS-1-128 lb_n3: a ground plane below the sensor, and scans that line up under Ouster's own
// SLAM poses only when expressed in the sensor frame).

#include "drivers/ouster/xyz_lut.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <unordered_map>

#include "drivers/ouster/ouster_decoder.hpp"
#include "drivers/ouster/tests/ouster_test_util.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers::ouster {
namespace {

// §3.6 written out literally, in double precision.
Eigen::Vector3d reference_point(const SensorMetadata& m, std::uint32_t u, std::uint32_t v,
                                double r_mm) {
  const double pi = std::numbers::pi;
  const double w = m.format.columns_per_frame;
  const double theta_e = 2.0 * pi * (1.0 - v / w);
  const double theta_a = -m.beam_azimuth_angles_deg[u] * pi / 180.0;
  const double phi = m.beam_altitude_angles_deg[u] * pi / 180.0;
  const double b03 = m.T_lidar_beam_mm(0, 3);
  const double b23 = m.T_lidar_beam_mm(2, 3);
  const double n = std::sqrt(b03 * b03 + b23 * b23);
  const Eigen::Vector3d p_lidar(
      (r_mm - n) * std::cos(theta_e + theta_a) * std::cos(phi) + b03 * std::cos(theta_e),
      (r_mm - n) * std::sin(theta_e + theta_a) * std::cos(phi) + b03 * std::sin(theta_e),
      (r_mm - n) * std::sin(phi) + b23);
  return 1e-3 * (m.T_sensor_lidar_mm.topLeftCorner<3, 3>() * p_lidar +
                 m.T_sensor_lidar_mm.topRightCorner<3, 1>());
}

SensorMetadata lb_n3_metadata() {
  return load_metadata(test::data_path("ouster/pcaps/OS-1-128_v2.3.0_1024x10.json"));
}

TEST(OusterGeometry, LutMatchesTheReferenceFormula) {
  SensorMetadata base = lb_n3_metadata();
  // The real calibration, then one with a vertical beam offset and a tilted, shifted mount.
  SensorMetadata tilted = base;
  tilted.T_lidar_beam_mm(2, 3) = 7.5;
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  t.topLeftCorner<3, 3>() =
      (Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized())).toRotationMatrix();
  t.topRightCorner<3, 1>() = Eigen::Vector3d(12.0, -40.0, 55.5);
  tilted.T_sensor_lidar_mm = t;
  for (const SensorMetadata* m : {&base, &tilted}) {
    const XyzLut lut(*m);
    double worst = 0.0;
    for (std::uint32_t u = 0; u < lut.rows(); u += 3) {
      for (std::uint32_t v = 0; v < lut.columns(); v += 7) {
        for (std::uint32_t r : {300U, 1234U, 9999U, 52000U, 200000U}) {
          const Eigen::Vector3d want = reference_point(*m, u, v, r);
          const Eigen::Vector3d got = lut.point(u, v, r).cast<double>();
          worst = std::max(worst, (got - want).norm() / std::max(1.0, want.norm()));
        }
      }
    }
    EXPECT_LT(worst, 2e-6) << "relative error (float arithmetic)";
  }
}

TEST(OusterGeometry, AnalyticProperties) {
  // Identity mount and no beam offset: the point is r along the beam's direction.
  SensorMetadata m = lb_n3_metadata();
  m.T_lidar_beam_mm = Eigen::Matrix4d::Identity();
  m.T_sensor_lidar_mm = Eigen::Matrix4d::Identity();
  const XyzLut lut(m);
  for (std::uint32_t u : {0U, 40U, 127U}) {
    for (std::uint32_t v : {0U, 256U, 700U}) {
      const Eigen::Vector3d p = lut.point(u, v, 10000).cast<double>();
      EXPECT_NEAR(p.norm(), 10.0, 1e-5);
      EXPECT_NEAR(std::asin(p.z() / p.norm()) * 180.0 / std::numbers::pi,
                  m.beam_altitude_angles_deg[u], 1e-4);
      // Encoder angle 2 pi (1 - v/W) minus the beam's azimuth offset.
      double expected_az = 360.0 * (1.0 - v / 1024.0) - m.beam_azimuth_angles_deg[u];
      double got_az = std::atan2(p.y(), p.x()) * 180.0 / std::numbers::pi;
      const double diff = std::remainder(got_az - expected_az, 360.0);
      EXPECT_NEAR(diff, 0.0, 1e-4);
    }
  }
  // With the real mount (lidar x points back, at the connector): column 0 looks along sensor -x.
  const XyzLut real(lb_n3_metadata());
  std::uint32_t flat_row = 0;
  for (std::uint32_t u = 0; u < 128; ++u) {
    if (std::abs(m.beam_altitude_angles_deg[u]) < std::abs(m.beam_altitude_angles_deg[flat_row]))
      flat_row = u;
  }
  const Eigen::Vector3f back = real.point(flat_row, 0, 20000);
  EXPECT_LT(back.x(), -19.9F);
  EXPECT_NEAR(back.z(), 0.036F, 0.05F);
  const Eigen::Vector3f forward = real.point(flat_row, 512, 20000);
  EXPECT_GT(forward.x(), 19.9F);
}

std::vector<LidarScan> lb_n3_scans() {
  OusterDecoder decoder(lb_n3_metadata());
  std::vector<LidarScan> scans;
  DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& s) { scans.push_back(s); };
  for (const auto& p :
       testutil::read_capture(test::data_path("ouster/pcaps/OS-1-128_v2.3.0_1024x10_lb_n3.pcap"))) {
    decoder.on_packet(p.view(), sinks);
  }
  decoder.flush(sinks);
  return scans;
}

TEST(OusterGeometry, GroundPlaneBelowTheSensor) {
  const auto scans = lb_n3_scans();
  ASSERT_EQ(scans.size(), 3U);
  for (const LidarScan& s : scans) {
    // Ranges: every return above the minimum range and below the RNG15 ceiling (32767 x 8 mm);
    // half of them within 30 m (a street).
    std::vector<float> ranges;
    for (std::size_t i = 0; i < s.size(); ++i) ranges.push_back(s.point(i).norm());
    std::sort(ranges.begin(), ranges.end());
    EXPECT_GT(ranges.front(), 0.2F);
    EXPECT_LT(ranges.back(), 262.2F);
    EXPECT_LT(ranges[ranges.size() / 2], 30.0F);
    // The road: the most common height of nearby low points, then a least-squares plane there.
    std::map<int, int> histogram;  // 5 cm bins
    for (std::size_t i = 0; i < s.size(); ++i) {
      const Eigen::Vector3f p = s.point(i);
      const float d = std::hypot(p.x(), p.y());
      if (d > 3.0F && d < 15.0F && p.z() < -0.5F)
        ++histogram[static_cast<int>(std::floor(p.z() / 0.05F))];
    }
    const auto mode =
        std::max_element(histogram.begin(), histogram.end(),
                         [](const auto& a, const auto& b) { return a.second < b.second; });
    const double ground_z = (mode->first + 0.5) * 0.05;
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    int inliers = 0;
    for (std::size_t i = 0; i < s.size(); ++i) {
      const Eigen::Vector3d p = s.point(i).cast<double>();
      const double d = std::hypot(p.x(), p.y());
      if (d < 3.0 || d > 15.0 || std::abs(p.z() - ground_z) > 0.2) continue;
      const Eigen::Vector3d a(p.x(), p.y(), 1.0);
      ata += a * a.transpose();
      atb += a * p.z();
      ++inliers;
    }
    const Eigen::Vector3d plane = ata.ldlt().solve(atb);  // z = a x + b y + c
    const Eigen::Vector3d normal = Eigen::Vector3d(-plane.x(), -plane.y(), 1.0).normalized();
    EXPECT_GT(inliers, 15000);
    EXPECT_LT(std::acos(normal.z()) * 180.0 / std::numbers::pi, 3.0) << "ground is level";
    EXPECT_GT(plane.z(), -2.3);  // a roof-mounted sensor: ground about 2 m below
    EXPECT_LT(plane.z(), -1.6);
  }
}

// p90 of nearest-neighbour distances from `query` (transformed by T) to `reference`.
double p90_nn_distance(const std::vector<Eigen::Vector3d>& reference,
                       const std::vector<Eigen::Vector3d>& query, const Eigen::Matrix4d& T) {
  constexpr double kVoxel = 0.5;
  const auto key = [](const Eigen::Vector3d& p) {
    const auto c = [](double x) {
      return static_cast<std::int64_t>(std::floor(x / kVoxel)) & 0x1FFFFF;
    };
    return (c(p.x()) << 42) | (c(p.y()) << 21) | c(p.z());
  };
  std::unordered_map<std::int64_t, std::vector<Eigen::Vector3d>> grid;
  for (const auto& p : reference) grid[key(p)].push_back(p);
  std::vector<double> d;
  for (const auto& q0 : query) {
    const Eigen::Vector3d q = T.topLeftCorner<3, 3>() * q0 + T.topRightCorner<3, 1>();
    double best = 1.0;
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find(key(q + kVoxel * Eigen::Vector3d(dx, dy, dz)));
          if (it == grid.end()) continue;
          for (const auto& r : it->second) best = std::min(best, (r - q).norm());
        }
      }
    }
    d.push_back(best);
  }
  std::sort(d.begin(), d.end());
  return d[d.size() * 9 / 10];
}

TEST(OusterGeometry, ScansAlignUnderReferencePosesInTheSensorFrame) {
  // OS-1-128_v2.3.0_1024x10_lb_n3_poses_kitti.txt: T_world_sensor per frame (KITTI 3x4 rows),
  // from Ouster's SLAM. The car moves ~0.25 m per frame.
  std::ifstream in(test::data_path("ouster/pcaps/OS-1-128_v2.3.0_1024x10_lb_n3_poses_kitti.txt"));
  std::vector<Eigen::Matrix4d> poses;
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  while (in >> T(0, 0) >> T(0, 1) >> T(0, 2) >> T(0, 3) >> T(1, 0) >> T(1, 1) >> T(1, 2) >>
         T(1, 3) >> T(2, 0) >> T(2, 1) >> T(2, 2) >> T(2, 3)) {
    poses.push_back(T);
  }
  ASSERT_EQ(poses.size(), 3U);
  const auto scans = lb_n3_scans();
  ASSERT_EQ(scans.size(), 3U);
  const auto near_points = [](const LidarScan& s, std::size_t stride) {
    std::vector<Eigen::Vector3d> out;
    for (std::size_t i = 0; i < s.size(); i += stride) {
      const Eigen::Vector3d p = s.point(i).cast<double>();
      if (p.norm() < 30.0) out.push_back(p);
    }
    return out;
  };
  std::vector<Eigen::Vector3d> reference = near_points(scans[0], 1);
  for (auto& p : reference)
    p = poses[0].topLeftCorner<3, 3>() * p + poses[0].topRightCorner<3, 1>();
  for (std::size_t k = 1; k < 3; ++k) {
    SCOPED_TRACE(k);
    const auto query = near_points(scans[k], 31);
    ASSERT_GT(query.size(), 2000U);
    Eigen::Matrix4d mirrored = poses[k];
    mirrored(0, 3) = -mirrored(0, 3);  // motion read in a frame with x pointing backwards
    const double with_pose = p90_nn_distance(reference, query, poses[k]);
    const double without = p90_nn_distance(reference, query, Eigen::Matrix4d::Identity());
    const double wrong_axis = p90_nn_distance(reference, query, mirrored);
    EXPECT_LT(with_pose, 0.2);
    EXPECT_GT(without, 1.4 * with_pose);
    EXPECT_GT(wrong_axis, 2.0 * with_pose);
  }
}

}  // namespace
}  // namespace livod::drivers::ouster

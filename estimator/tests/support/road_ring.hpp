#pragma once
// One ring of a spinning LiDAR crossing a 0.5 m voxel of flat road (header-only test support for
// the plane spread test, estimator/map/plane.hpp): the hits of an arc at a ground range, scattered
// along their rays by range noise only, each with its range + bearing covariance. Their fan of
// rays is what FAST-LIVO2's planarity test takes for a plane.

#include <Eigen/Core>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "estimator/map/plane.hpp"
#include "estimator/map/point_covariance.hpp"

namespace livod::estimator::test_support {

struct RoadRing {
  double range_m = 10.0;         // ground range of the ring from below the sensor
  double sensor_height_m = 1.8;  // above the road
  double road_z_m = 0.0;         // world z of the road; the sensor is at (0, 0, road + height)
  double y_begin_m = -0.24;      // the arc across the voxel, from y_begin to y_end
  double y_end_m = 0.24;
  int points = 30;
};

inline std::vector<CovPoint> road_ring(std::mt19937& rng, const RoadRing& ring) {
  const Eigen::Vector3d sensor(0.0, 0.0, ring.road_z_m + ring.sensor_height_m);
  PointNoise noise;
  noise.range_sigma_m = 0.015;                                 // the OS1's datasheet
  noise.bearing_sigma_rad = 0.065 * std::numbers::pi / 180.0;  // half its divergence
  std::normal_distribution<double> g(0.0, noise.range_sigma_m);
  std::vector<CovPoint> pts;
  for (int i = 0; i < ring.points; ++i) {
    const double y = ring.y_begin_m + (ring.y_end_m - ring.y_begin_m) * i / (ring.points - 1);
    const Eigen::Vector3d hit(std::sqrt(ring.range_m * ring.range_m - y * y), y, ring.road_z_m);
    const Eigen::Vector3d ray = (hit - sensor).normalized();
    CovPoint c;
    c.p = hit + g(rng) * ray;
    c.cov = point_covariance(hit - sensor, noise);  // sensor axes = world axes here
    pts.push_back(c);
  }
  return pts;
}

}  // namespace livod::estimator::test_support

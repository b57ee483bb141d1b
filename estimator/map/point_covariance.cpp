#include "estimator/map/point_covariance.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "core/so3.hpp"

namespace livod::estimator {

Eigen::Matrix3d point_covariance(const Eigen::Vector3d& p, const PointNoise& noise,
                                 const std::optional<Eigen::Vector3d>& normal) {
  const double r = p.norm();
  if (r < 1e-9) return Eigen::Matrix3d::Identity() * noise.range_sigma_m * noise.range_sigma_m;
  const Eigen::Vector3d d = p / r;
  // Two unit vectors perpendicular to the ray.
  const Eigen::Vector3d helper =
      std::abs(d.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
  const Eigen::Vector3d n1 = d.cross(helper).normalized();
  const Eigen::Vector3d n2 = d.cross(n1);
  Eigen::Matrix<double, 3, 2> N;
  N.col(0) = n1;
  N.col(1) = n2;
  const double s2 = std::pow(std::sin(noise.bearing_sigma_rad), 2);
  const Eigen::Matrix<double, 3, 2> A =
      r * so3::hat(d) * N;  // 3x2: bearing perturbation -> position
  double range_var = noise.range_sigma_m * noise.range_sigma_m;
  if (normal) {
    const double cos_inc = std::abs(d.dot(normal->normalized()));
    const double inc = std::min(std::acos(std::clamp(cos_inc, 0.0, 1.0)), noise.max_incidence_rad);
    range_var += std::pow(r * std::tan(inc) * noise.bearing_sigma_rad, 2);
  }
  return range_var * d * d.transpose() + s2 * A * A.transpose();
}

}  // namespace livod::estimator

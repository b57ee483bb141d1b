#include "estimator/map/point_covariance.hpp"

#include <algorithm>
#include <cmath>

namespace livod::estimator {

double range_growth_variance(double r, double cos_inc, const PointNoise& noise) {
  if (noise.range_limit_m <= 0.0 || noise.sigma_at_limit_m <= 0.0) return 0.0;
  const double cos_eff = std::max(std::abs(cos_inc), std::cos(noise.max_incidence_rad));
  const double ratio = r / noise.range_limit_m;
  const double q2 = std::min(1.0, ratio * ratio / cos_eff);
  return noise.sigma_at_limit_m * noise.sigma_at_limit_m * std::pow(q2, 1.2);
}

Eigen::Matrix3d point_covariance(const Eigen::Vector3d& p, const PointNoise& noise,
                                 const std::optional<Eigen::Vector3d>& normal) {
  const double r = p.norm();
  if (r < 1e-9) return Eigen::Matrix3d::Identity() * noise.range_sigma_m * noise.range_sigma_m;
  const Eigen::Vector3d d = p / r;
  // The bearing term r^2 sin^2(sigma_b) [d]x N N^T [d]x^T with N two unit vectors across the ray:
  // [d]x N spans the same plane, so it is r^2 sin^2(sigma_b) (I - d d^T).
  const double sin_b = std::sin(noise.bearing_sigma_rad);
  const double bearing_var = r * r * sin_b * sin_b;
  double range_var = noise.range_sigma_m * noise.range_sigma_m;
  if (!normal) range_var += range_growth_variance(r, 1.0, noise);
  if (normal) {
    // tan(incidence) from its cosine, the incidence clamped to max_incidence_rad.
    const double cos_inc = std::min(1.0, std::abs(d.dot(normal->normalized())));
    range_var += range_growth_variance(r, cos_inc, noise);
    const double max_tan = std::tan(noise.max_incidence_rad);
    const double tan_inc =
        cos_inc > 0.0 ? std::min(std::sqrt(1.0 - cos_inc * cos_inc) / cos_inc, max_tan) : max_tan;
    range_var += std::pow(r * tan_inc * noise.bearing_sigma_rad, 2);
  }
  return (range_var - bearing_var) * d * d.transpose() + bearing_var * Eigen::Matrix3d::Identity();
}

}  // namespace livod::estimator

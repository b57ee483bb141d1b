#pragma once
// Measurement covariance of a LiDAR point (VoxelMap, fast-livo2-notes.md 1.3): range noise along
// the ray plus bearing noise across it,
//   S = sigma_r^2 d d^T + r^2 [d]x N diag(sin^2 sigma_b, sin^2 sigma_b) N^T [d]x^T,
// and - the term FAST-LIVO2's released code comments out - the incidence-angle effect: on a
// surface seen at incidence alpha, the bearing uncertainty smears the hit along the ray by
// r tan(alpha) sigma_b, which is added to the range variance when the surface normal is known.

#include <Eigen/Core>
#include <optional>

namespace livod::estimator {

struct PointNoise {
  double range_sigma_m = 0.02;                                       // FAST-LIVO2 dept_err
  double bearing_sigma_rad = 0.05 * 3.14159265358979323846 / 180.0;  // beam_err (deg there)
  double max_incidence_rad = 1.4;  // clamp tan() near grazing incidence (80 deg)
};

// Covariance of point p (sensor frame). `normal` (any frame consistent with p) enables the
// incidence term.
Eigen::Matrix3d point_covariance(const Eigen::Vector3d& p, const PointNoise& noise,
                                 const std::optional<Eigen::Vector3d>& normal = std::nullopt);

}  // namespace livod::estimator

#pragma once
// Measurement covariance of a LiDAR point (VoxelMap, fast-livo2-notes.md 1.3): range noise along
// the ray plus bearing noise across it,
//   S = sigma_r^2 d d^T + r^2 [d]x N diag(sin^2 sigma_b, sin^2 sigma_b) N^T [d]x^T,
// and - the term FAST-LIVO2's released code comments out - the incidence-angle effect: on a
// surface seen at incidence alpha, the bearing uncertainty smears the hit along the ray by
// r tan(alpha) sigma_b, which is added to the range variance when the surface normal is known.
//
// The range noise of a real LiDAR is not constant: it grows as the echo weakens towards the
// detection limit (far, grazing or dark targets). With range_limit_m > 0 the range variance gets
//   (sigma_at_limit_m q^1.2)^2,  q = r / (range_limit_m sqrt(cos alpha)), q capped at 1,
// the Ouster OS1 datasheet's precision against SNR (1.5 cm at SNR > 250, 3 cm at 100, 10 cm at 12
// fits SNR^-0.6) with the echo falling as cos(alpha) / r^2; range_limit_m is the detection limit
// of a typical target seen head-on (the estimator does not know each target's reflectivity). A
// return exists only within its limit, hence the cap. Without a known surface alpha is 0.

#include <Eigen/Core>
#include <optional>

namespace livod::estimator {

struct PointNoise {
  double range_sigma_m = 0.02;                                       // FAST-LIVO2 dept_err
  double bearing_sigma_rad = 0.05 * 3.14159265358979323846 / 180.0;  // beam_err (deg there)
  double max_incidence_rad = 1.4;  // clamp tan() near grazing incidence (80 deg)
  double range_limit_m = 0.0;      // detection limit of a typical target head-on; 0: no growth
  double sigma_at_limit_m = 0.0;   // range noise at the detection limit
};

// The range variance the growth towards the detection limit adds at range r and incidence cosine
// cos_inc (clamped to the largest incidence modelled); 0 without a range limit.
double range_growth_variance(double r, double cos_inc, const PointNoise& noise);

// Covariance of point p (sensor frame). `normal` (any frame consistent with p) enables the
// incidence term.
Eigen::Matrix3d point_covariance(const Eigen::Vector3d& p, const PointNoise& noise,
                                 const std::optional<Eigen::Vector3d>& normal = std::nullopt);

}  // namespace livod::estimator

#pragma once
// Plane fitting with uncertainty (VoxelMap, fast-livo2-notes.md 1.3). The plane of N points is
// the centroid q and the eigenvector n of the smallest eigenvalue of their scatter matrix; its
// 6x6 covariance over (n, q) is propagated from every point's 3x3 covariance through the
// analytic Jacobians
//   dq/dp_j = I / N
//   dn/dp_j = sum_{m=2,3} u_m [((p_j - q).n) u_m^T + ((p_j - q).u_m) n^T] / (N (lambda_1 -
//   lambda_m))
// (first-order eigenvector perturbation of the scatter matrix).

#include <Eigen/Core>
#include <array>
#include <optional>
#include <vector>

namespace livod::estimator {

struct CovPoint {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();    // world frame
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();  // world frame
};

// A fitted plane with its full covariance (the voxel map keeps the reduced MapPlane below).
struct Plane {
  bool is_plane = false;
  // Flat, but spread along one direction only beyond the points' noise: a line (one ring's hits in
  // a voxel), not a plane yet (fit_plane's min_spread_ratio). is_plane is false.
  bool line = false;
  int points = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit, smallest-eigenvalue eigenvector
  double d = 0.0;                                     // n.x + d = 0 on the plane
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 0.0;                                    // sqrt(largest eigenvalue)
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();  // ascending
  Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Zero();  // over (n, q)
};

// Fits `points`; is_plane = smallest eigenvalue < min_eigen_value. Needs >= 3 points.
//
// min_spread_ratio > 0 also asks that the points span the plane: their spread along its narrower
// in-plane direction u (the middle eigenvalue) must be at least min_spread_ratio times their mean
// noise variance along u (u^T C_j u). Points that fail it are a line made flat by noise, and
// marked `line` instead: one ring's hits across a voxel scatter only along their rays (the range
// noise), and the smallest eigenvector is then the normal of the fan of rays - a plane through the
// sensor, tilted from the surface by the rays' incidence - which the first-order covariance above
// calls exact, since noise along the rays cannot tilt it (docs/estimator.md "Lines are not
// planes"). 0: FAST-LIVO2's test alone.
Plane fit_plane(const std::vector<CovPoint>& points, double min_eigen_value,
                double min_spread_ratio = 0.0);

// What the voxel map keeps of a fitted plane for association: the plane, its in-plane extent and
// its uncertainty reduced to what the point-to-plane variance needs. With e = p - q and
// J = [e^T, -n^T] over (n, q),
//   J cov J^T = e^T C_nn e - 2 e^T (C_nq n) + n^T C_qq n
// so 6 + 3 + 1 numbers replace the 6x6 covariance: matching a point reads three cache lines
// instead of six (association is bound by memory latency), and the same variance comes out.
struct MapPlane {
  bool is_plane = false;
  bool line = false;  // Plane::line
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double d = 0.0;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double extent2 = 0.0;            // (3 radius)^2: points farther in-plane do not belong to it
  std::array<double, 6> cov_nn{};  // C_nn: xx yy zz xy xz yz
  Eigen::Vector3d cov_nq_n = Eigen::Vector3d::Zero();  // C_nq n
  double n_cov_qq_n = 0.0;                             // n^T C_qq n
};
MapPlane map_plane(const Plane& plane);

// Running first and second moments of points about a fixed origin near them (the sums stay small,
// so the scatter keeps its precision far from the world origin): what a map node keeps of its
// points once it stores no more of them (LioParams::max_cov_points).
struct PointMoments {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double count = 0.0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();    // of p - origin
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();  // of (p - origin)(p - origin)^T
  void add(const Eigen::Vector3d& p) {
    const Eigen::Vector3d e = p - origin;
    count += 1.0;
    sum += e;
    outer.noalias() += e * e.transpose();
  }
};

// The plane of every point in `moments`, with the uncertainty of `reference` - a plane fitted
// (fit_plane) from `reference_points` of those points - scaled by reference_points /
// moments.count: to first order the plane of N points like the reference's is known N / n times
// better (both blocks of the Jacobian above scale as 1 / N), and the normal moves too little for
// the covariance's orientation to change. nullopt when the points are no longer planar (smallest
// eigenvalue >= min_eigen_value).
std::optional<MapPlane> refit_map_plane(const PointMoments& moments, const MapPlane& reference,
                                        double reference_points, double min_eigen_value);

// Signed point-to-plane distance and its variance (plane uncertainty + point uncertainty):
//   sigma^2 = J cov J^T + n^T S_p n,  J = [(p - q)^T, -n^T]
struct PlaneResidual {
  double distance = 0.0;
  double variance = 0.0;
};
PlaneResidual plane_residual(const Plane& plane, const Eigen::Vector3d& p,
                             const Eigen::Matrix3d& point_cov);
// The same from the map's reduced form (equal up to round-off).
PlaneResidual plane_residual(const MapPlane& plane, const Eigen::Vector3d& p,
                             const Eigen::Matrix3d& point_cov);

// A point to test against planes: its position and range + bearing covariance, and what the
// incidence-angle term needs. On a surface seen at incidence alpha the bearing uncertainty smears
// the hit along the ray by r tan(alpha) sigma_b (point_covariance.hpp); along the plane normal
// that adds (r sigma_b)^2 sin^2(alpha) to the variance. It depends on the plane, so it is added
// per candidate plane (FAST-LIVO2's released code leaves the term out).
struct PointQuery {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();    // world
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();  // world, range + bearing
  Eigen::Vector3d ray = Eigen::Vector3d::Zero();  // unit, sensor to point; zero: no incidence term
  double incidence_var = 0.0;                     // (r sigma_b)^2
  double max_tan2 = 0.0;  // tan^2 of the largest incidence modelled (grazing hits are clamped)
  // The range noise growing towards the detection limit (point_covariance.hpp): (r / limit)^2
  // (0: no growth) and the variance at the limit. `cov` holds its head-on value; the rest, which
  // depends on the plane's incidence, is added per candidate plane.
  double range_q2 = 0.0;
  double var_at_limit = 0.0;
  // The association gate in sigmas for this point's LiDAR; 0: the map's (LioParams::sigma_num).
  double gate_sigmas = 0.0;
};
// The incidence-dependent variance along `normal`: (r sigma_b tan(alpha))^2 cos^2(alpha), and the
// range noise growth beyond its head-on value, times cos^2(alpha); alpha clamped to the largest
// incidence.
double incidence_variance(const PointQuery& q, const Eigen::Vector3d& normal);
// Residual of q: plane uncertainty + n^T cov n + the incidence term.
PlaneResidual plane_residual(const MapPlane& plane, const PointQuery& q);

// The Jacobian of (n, q) with respect to point j (for tests and diagnostics).
Eigen::Matrix<double, 6, 3> plane_jacobian(const std::vector<CovPoint>& points, const Plane& plane,
                                           std::size_t j);

}  // namespace livod::estimator

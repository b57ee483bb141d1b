#include "estimator/map/plane.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace livod::estimator {
namespace {

struct Decomposition {
  Eigen::Vector3d center;
  Eigen::Vector3d values;  // ascending
  Eigen::Matrix3d vectors;
};

Decomposition decompose(const std::vector<CovPoint>& points) {
  Decomposition out;
  const double n = static_cast<double>(points.size());
  out.center.setZero();
  for (const auto& p : points) out.center += p.p;
  out.center /= n;
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : points) {
    const Eigen::Vector3d e = p.p - out.center;
    scatter += e * e.transpose();
  }
  scatter /= n;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(scatter);
  out.values = es.eigenvalues();
  out.vectors = es.eigenvectors();
  return out;
}

Eigen::Matrix<double, 6, 3> jacobian(const Decomposition& dec, const Eigen::Vector3d& n,
                                     const Eigen::Vector3d& p, double count) {
  Eigen::Matrix<double, 6, 3> J = Eigen::Matrix<double, 6, 3>::Zero();
  const Eigen::Vector3d e = p - dec.center;
  for (int m = 1; m < 3; ++m) {
    const double gap = dec.values(0) - dec.values(m);
    if (std::abs(gap) < 1e-12) continue;  // degenerate: no information along this direction
    const Eigen::Vector3d um = dec.vectors.col(m);
    J.topRows<3>() += um * (e.dot(n) * um.transpose() + e.dot(um) * n.transpose()) / (count * gap);
  }
  J.bottomRows<3>() = Eigen::Matrix3d::Identity() / count;
  return J;
}

}  // namespace

Plane fit_plane(const std::vector<CovPoint>& points, double min_eigen_value) {
  Plane plane;
  plane.points = static_cast<int>(points.size());
  if (points.size() < 3) return plane;
  const Decomposition dec = decompose(points);
  plane.center = dec.center;
  plane.eigenvalues = dec.values;
  plane.normal = dec.vectors.col(0);
  plane.d = -plane.normal.dot(plane.center);
  plane.radius = std::sqrt(std::max(0.0, dec.values(2)));
  plane.is_plane = dec.values(0) < min_eigen_value;
  if (!plane.is_plane) return plane;
  const double count = static_cast<double>(points.size());
  for (const auto& p : points) {
    const Eigen::Matrix<double, 6, 3> J = jacobian(dec, plane.normal, p.p, count);
    plane.cov += J * p.cov * J.transpose();
  }
  return plane;
}

Eigen::Matrix<double, 6, 3> plane_jacobian(const std::vector<CovPoint>& points, const Plane& plane,
                                           std::size_t j) {
  const Decomposition dec = decompose(points);
  return jacobian(dec, plane.normal, points[j].p, static_cast<double>(points.size()));
}

PlaneResidual plane_residual(const Plane& plane, const Eigen::Vector3d& p,
                             const Eigen::Matrix3d& point_cov) {
  PlaneResidual r;
  r.distance = plane.normal.dot(p) + plane.d;
  Eigen::Matrix<double, 1, 6> J;
  J.leftCols<3>() = (p - plane.center).transpose();
  J.rightCols<3>() = -plane.normal.transpose();
  r.variance = (J * plane.cov * J.transpose())(0, 0) + plane.normal.dot(point_cov * plane.normal);
  return r;
}

}  // namespace livod::estimator

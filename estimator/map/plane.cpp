#include "estimator/map/plane.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
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

// d n / d p_j (the top block of the Jacobian; the centre's is I / N).
Eigen::Matrix3d normal_jacobian(const Decomposition& dec, const Eigen::Vector3d& n,
                                const Eigen::Vector3d& p, double count) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  const Eigen::Vector3d e = p - dec.center;
  for (int m = 1; m < 3; ++m) {
    const double gap = dec.values(0) - dec.values(m);
    if (std::abs(gap) < 1e-12) continue;  // degenerate: no information along this direction
    const Eigen::Vector3d um = dec.vectors.col(m);
    A += um * (e.dot(n) * um.transpose() + e.dot(um) * n.transpose()) / (count * gap);
  }
  return A;
}

Eigen::Matrix<double, 6, 3> jacobian(const Decomposition& dec, const Eigen::Vector3d& n,
                                     const Eigen::Vector3d& p, double count) {
  Eigen::Matrix<double, 6, 3> J;
  J.topRows<3>() = normal_jacobian(dec, n, p, count);
  J.bottomRows<3>() = Eigen::Matrix3d::Identity() / count;
  return J;
}

// Whether the points' spread along u (an eigenvector of their scatter, eigenvalue `spread`) is
// at least `ratio` times their mean noise variance along it.
bool spans(const std::vector<CovPoint>& points, const Eigen::Vector3d& u, double spread,
           double ratio) {
  double noise = 0.0;
  for (const auto& p : points) noise += u.dot(p.cov * u);
  return spread >= ratio * noise / static_cast<double>(points.size());
}

}  // namespace

Plane fit_plane(const std::vector<CovPoint>& points, double min_eigen_value,
                double min_spread_ratio) {
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
  if (plane.is_plane && min_spread_ratio > 0.0 &&
      !spans(points, dec.vectors.col(1), dec.values(1), min_spread_ratio)) {
    plane.is_plane = false;
    plane.line = true;
  }
  if (!plane.is_plane) return plane;
  // cov = sum_j J_j C_j J_j^T with J_j = [A_j; I/N]: accumulated per block (nn, nq, qq), which
  // is less than half the work of the full 6x3 products.
  const double count = static_cast<double>(points.size());
  Eigen::Matrix3d nn = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d nq = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d qq = Eigen::Matrix3d::Zero();
  for (const auto& p : points) {
    const Eigen::Matrix3d A = normal_jacobian(dec, plane.normal, p.p, count);
    const Eigen::Matrix3d AC = A * p.cov;
    nn.noalias() += AC * A.transpose();
    nq += AC;
    qq += p.cov;
  }
  nq /= count;
  qq /= count * count;
  plane.cov.topLeftCorner<3, 3>() = nn;
  plane.cov.topRightCorner<3, 3>() = nq;
  plane.cov.bottomLeftCorner<3, 3>() = nq.transpose();
  plane.cov.bottomRightCorner<3, 3>() = qq;
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

namespace livod::estimator {

MapPlane map_plane(const Plane& plane) {
  MapPlane m;
  m.is_plane = plane.is_plane;
  m.line = plane.line;
  m.normal = plane.normal;
  m.d = plane.d;
  m.center = plane.center;
  m.extent2 = 9.0 * plane.radius * plane.radius;
  const auto C = plane.cov.topLeftCorner<3, 3>();
  m.cov_nn = {C(0, 0), C(1, 1), C(2, 2), C(0, 1), C(0, 2), C(1, 2)};
  m.cov_nq_n = plane.cov.topRightCorner<3, 3>() * plane.normal;
  m.n_cov_qq_n = plane.normal.dot(plane.cov.bottomRightCorner<3, 3>() * plane.normal);
  return m;
}

double incidence_variance(const PointQuery& q, const Eigen::Vector3d& normal) {
  if (q.incidence_var <= 0.0 && q.range_q2 <= 0.0) return 0.0;
  const double c = normal.dot(q.ray);
  const double cos2 = c * c;
  double variance = 0.0;
  if (q.incidence_var > 0.0) {
    // tan^2(alpha) cos^2(alpha) = sin^2(alpha) = 1 - cos^2; beyond the largest incidence,
    // tan^2(max) cos^2(alpha).
    const double tan2 = cos2 > 0.0 ? (1.0 - cos2) / cos2 : q.max_tan2;
    variance += q.incidence_var * std::min(tan2, q.max_tan2) * cos2;
  }
  if (q.range_q2 > 0.0) {
    // q^2 = (r / limit)^2 / cos(alpha), capped at 1 (range_growth_variance).
    const double cos_eff = std::sqrt(std::max(cos2, 1.0 / (1.0 + q.max_tan2)));
    const double head_on = std::pow(std::min(1.0, q.range_q2), 1.2);
    const double here = std::pow(std::min(1.0, q.range_q2 / cos_eff), 1.2);
    variance += q.var_at_limit * (here - head_on) * cos2;
  }
  return variance;
}

PlaneResidual plane_residual(const MapPlane& plane, const PointQuery& q) {
  PlaneResidual r = plane_residual(plane, q.p, q.cov);
  r.variance += incidence_variance(q, plane.normal);
  return r;
}

PlaneResidual plane_residual(const MapPlane& plane, const Eigen::Vector3d& p,
                             const Eigen::Matrix3d& point_cov) {
  PlaneResidual r;
  const Eigen::Vector3d& n = plane.normal;
  r.distance = n.dot(p) + plane.d;
  const Eigen::Vector3d e = p - plane.center;
  const auto& c = plane.cov_nn;
  const double e_cnn_e = c[0] * e.x() * e.x() + c[1] * e.y() * e.y() + c[2] * e.z() * e.z() +
                         2.0 * (c[3] * e.x() * e.y() + c[4] * e.x() * e.z() + c[5] * e.y() * e.z());
  r.variance = e_cnn_e - 2.0 * e.dot(plane.cov_nq_n) + plane.n_cov_qq_n + n.dot(point_cov * n);
  return r;
}

std::optional<MapPlane> refit_map_plane(const PointMoments& moments, const MapPlane& reference,
                                        double reference_points, double min_eigen_value) {
  const Eigen::Vector3d mean = moments.sum / moments.count;
  const Eigen::Matrix3d scatter = moments.outer / moments.count - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(scatter);
  if (!(es.eigenvalues()(0) < min_eigen_value)) return std::nullopt;
  MapPlane m = reference;
  m.normal = es.eigenvectors().col(0);
  // The eigenvector's sign is arbitrary: keep the reference's, so that the covariance terms
  // that are odd in n (C_nq n) keep theirs.
  if (m.normal.dot(reference.normal) < 0.0) m.normal = -m.normal;
  m.center = moments.origin + mean;
  m.d = -m.normal.dot(m.center);
  m.extent2 = 9.0 * std::max(0.0, es.eigenvalues()(2));
  const double scale = reference_points / moments.count;
  for (double& c : m.cov_nn) c *= scale;
  m.cov_nq_n *= scale;
  m.n_cov_qq_n *= scale;
  return m;
}

}  // namespace livod::estimator

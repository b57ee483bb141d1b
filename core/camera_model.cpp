#include "core/camera_model.hpp"

#include <Eigen/LU>
#include <cmath>

namespace livod {
namespace {

constexpr double kMinDepth = 1e-6;

}  // namespace

CameraIntrinsics CameraIntrinsics::scaled(double scale) const {
  CameraIntrinsics k = *this;
  k.width = static_cast<int>(std::lround(width * scale));
  k.height = static_cast<int>(std::lround(height * scale));
  k.fx *= scale;
  k.fy *= scale;
  // Pixel centres: x_new + 0.5 = (x_old + 0.5) * scale
  k.cx = (cx + 0.5) * scale - 0.5;
  k.cy = (cy + 0.5) * scale - 0.5;
  return k;
}

Eigen::Vector2d CameraModel::distort_radtan(const Eigen::Vector2d& m, Eigen::Matrix2d* J) const {
  const double k1 = k_.distortion[0];
  const double k2 = k_.distortion[1];
  const double p1 = k_.distortion[2];
  const double p2 = k_.distortion[3];
  const double k3 = k_.radtan_k3;
  const double x = m.x();
  const double y = m.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2;
  const Eigen::Vector2d d(x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
                          y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y);
  if (J != nullptr) {
    const double dradial_dr2 = k1 + 2.0 * k2 * r2 + 3.0 * k3 * r2 * r2;
    (*J)(0, 0) = radial + x * dradial_dr2 * 2.0 * x + 2.0 * p1 * y + p2 * 6.0 * x;
    (*J)(0, 1) = x * dradial_dr2 * 2.0 * y + 2.0 * p1 * x + p2 * 2.0 * y;
    (*J)(1, 0) = y * dradial_dr2 * 2.0 * x + p1 * 2.0 * x + 2.0 * p2 * y;
    (*J)(1, 1) = radial + y * dradial_dr2 * 2.0 * y + p1 * 6.0 * y + 2.0 * p2 * x;
  }
  return d;
}

std::optional<Eigen::Vector2d> CameraModel::project(const Eigen::Vector3d& p,
                                                    Eigen::Matrix<double, 2, 3>* J) const {
  if (k_.model == CameraIntrinsics::Model::kPinholeRadtan) {
    if (p.z() <= kMinDepth) return std::nullopt;
    const double iz = 1.0 / p.z();
    const Eigen::Vector2d m(p.x() * iz, p.y() * iz);
    Eigen::Matrix2d Jd;
    const Eigen::Vector2d d = distort_radtan(m, J != nullptr ? &Jd : nullptr);
    if (J != nullptr) {
      Eigen::Matrix<double, 2, 3> Jm;
      Jm << iz, 0.0, -p.x() * iz * iz, 0.0, iz, -p.y() * iz * iz;
      Eigen::Matrix2d F = Eigen::Matrix2d::Zero();
      F(0, 0) = k_.fx;
      F(1, 1) = k_.fy;
      *J = F * Jd * Jm;
    }
    return Eigen::Vector2d(k_.fx * d.x() + k_.cx, k_.fy * d.y() + k_.cy);
  }
  // Equidistant: theta = atan2(r, z), theta_d = theta (1 + k1 th^2 + k2 th^4 + k3 th^6 + k4 th^8),
  // pixel = f * theta_d * (x, y) / r + c.
  const double r = std::hypot(p.x(), p.y());
  const double theta = std::atan2(r, p.z());
  if (theta >= M_PI - 1e-6) return std::nullopt;
  const double t2 = theta * theta;
  const auto& k = k_.distortion;
  const double poly = 1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])));
  const double theta_d = theta * poly;
  Eigen::Vector2d u;
  if (r < 1e-12) {
    // On the axis theta_d / r -> 1 / z.
    const double s = 1.0 / p.z();
    if (J != nullptr) {
      *J << k_.fx * s, 0.0, 0.0, 0.0, k_.fy * s, 0.0;
    }
    return Eigen::Vector2d(k_.cx, k_.cy);
  }
  const double s = theta_d / r;
  u = Eigen::Vector2d(s * p.x(), s * p.y());
  if (J != nullptr) {
    // d theta_d / d theta
    const double dpoly =
        1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
    const double rho2 = r * r + p.z() * p.z();
    // d theta / d p = (z * (x, y) / r, -r) / rho2
    const Eigen::Vector3d dtheta(p.z() * p.x() / (r * rho2), p.z() * p.y() / (r * rho2), -r / rho2);
    // d r / d p = (x / r, y / r, 0)
    const Eigen::Vector3d dr(p.x() / r, p.y() / r, 0.0);
    const Eigen::Vector3d ds = (dpoly * dtheta * r - theta_d * dr) / (r * r);
    Eigen::Matrix<double, 2, 3> Ju;
    Ju.row(0) = p.x() * ds.transpose();
    Ju.row(1) = p.y() * ds.transpose();
    Ju(0, 0) += s;
    Ju(1, 1) += s;
    Ju.row(0) *= k_.fx;
    Ju.row(1) *= k_.fy;
    *J = Ju;
  }
  return Eigen::Vector2d(k_.fx * u.x() + k_.cx, k_.fy * u.y() + k_.cy);
}

std::optional<Eigen::Vector3d> CameraModel::unproject(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d d((pixel.x() - k_.cx) / k_.fx, (pixel.y() - k_.cy) / k_.fy);
  if (k_.model == CameraIntrinsics::Model::kPinholeRadtan) {
    // Gauss-Newton on distort(m) = d, starting from m = d.
    Eigen::Vector2d m = d;
    for (int i = 0; i < 20; ++i) {
      Eigen::Matrix2d J;
      const Eigen::Vector2d e = distort_radtan(m, &J) - d;
      if (e.squaredNorm() < 1e-24) break;
      m -= J.inverse() * e;  // 2x2: closed-form inverse
    }
    Eigen::Matrix2d J;
    if ((distort_radtan(m, &J) - d).norm() > 1e-9) return std::nullopt;
    return Eigen::Vector3d(m.x(), m.y(), 1.0).normalized();
  }
  // Equidistant: solve theta (1 + ...) = |d| for theta with Newton.
  const double theta_d = d.norm();
  if (theta_d < 1e-15) return Eigen::Vector3d(0.0, 0.0, 1.0);
  const auto& k = k_.distortion;
  double theta = theta_d;
  for (int i = 0; i < 30; ++i) {
    const double t2 = theta * theta;
    const double f = theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])))) - theta_d;
    const double df =
        1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
    const double step = f / df;
    theta -= step;
    if (std::abs(step) < 1e-15) break;
  }
  if (!(theta >= 0.0 && theta < M_PI)) return std::nullopt;
  {
    // Past the lens's valid field of view the polynomial folds back (d theta_d / d theta <= 0) and
    // Newton can land on the wrong branch: reject instead of returning a wrong ray.
    const double t2 = theta * theta;
    const double f = theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])))) - theta_d;
    const double df =
        1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
    if (std::abs(f) > 1e-9 || df <= 0.0) return std::nullopt;
  }
  const Eigen::Vector2d dir = d / theta_d;
  return Eigen::Vector3d(std::sin(theta) * dir.x(), std::sin(theta) * dir.y(), std::cos(theta));
}

}  // namespace livod

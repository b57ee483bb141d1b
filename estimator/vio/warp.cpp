#include "estimator/vio/warp.hpp"

#include <cmath>

namespace livod::estimator::vio {

std::optional<Eigen::Matrix2d> affine_warp(const CameraModel& camera,
                                           const Eigen::Isometry3d& T_cur_ref,
                                           const Eigen::Vector2d& px_ref,
                                           const Eigen::Vector3d& p_ref,
                                           const Eigen::Vector3d& n_ref, double half) {
  const double n_dot_p = n_ref.dot(p_ref);
  // The pixel `offset` away from px_ref, through the plane, in the current image.
  auto through_plane = [&](const Eigen::Vector2d& offset) -> std::optional<Eigen::Vector2d> {
    const auto ray = camera.unproject(px_ref + offset);
    if (!ray) return std::nullopt;
    const double denom = n_ref.dot(*ray);
    // Grazing rays (the plane nearly edge-on) give no stable intersection.
    if (std::abs(denom) < 1e-6) return std::nullopt;
    const double depth = n_dot_p / denom;
    if (!(depth > 0.0)) return std::nullopt;
    return camera.project(T_cur_ref * (depth * *ray));
  };
  const auto xp = through_plane({half, 0.0});
  const auto xm = through_plane({-half, 0.0});
  const auto yp = through_plane({0.0, half});
  const auto ym = through_plane({0.0, -half});
  if (!xp || !xm || !yp || !ym) return std::nullopt;
  Eigen::Matrix2d A;
  A.col(0) = (*xp - *xm) / (2.0 * half);
  A.col(1) = (*yp - *ym) / (2.0 * half);
  return A;
}

int reference_level_offset(const Eigen::Matrix2d& A_ref_cur) {
  const double det = std::abs(A_ref_cur.determinant());
  if (!(det > 0.0)) return 0;
  // Linear scale sqrt(det) = 2^s: s = log2(det) / 2.
  return static_cast<int>(std::lround(0.5 * std::log2(det)));
}

}  // namespace livod::estimator::vio

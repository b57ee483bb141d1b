#include "estimator/vio/warp.hpp"

#include <cmath>

namespace livod::estimator::vio {

std::optional<Eigen::Matrix2d> affine_warp(const CameraModel& camera,
                                           const Eigen::Isometry3d& T_cur_ref,
                                           const Eigen::Vector3d& p_ref,
                                           const Eigen::Vector3d& n_ref) {
  // Two tangent directions of the plane.
  const Eigen::Vector3d helper =
      std::abs(n_ref.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  Eigen::Matrix<double, 3, 2> B;
  B.col(0) = n_ref.cross(helper).normalized();
  B.col(1) = n_ref.cross(B.col(0));
  Eigen::Matrix<double, 2, 3> J_ref;
  Eigen::Matrix<double, 2, 3> J_cur;
  if (!camera.project(p_ref, &J_ref) || !camera.project(T_cur_ref * p_ref, &J_cur)) {
    return std::nullopt;
  }
  const Eigen::Matrix2d M_ref = J_ref * B;
  // Edge-on: the surface covers no area in the reference image.
  if (std::abs(M_ref.determinant()) < 1e-9 * M_ref.squaredNorm()) return std::nullopt;
  return Eigen::Matrix2d(J_cur * T_cur_ref.linear() * B * M_ref.inverse());
}

int reference_level_offset(const Eigen::Matrix2d& A_ref_cur) {
  const double det = std::abs(A_ref_cur.determinant());
  if (!(det > 0.0)) return 0;
  // Linear scale sqrt(det) = 2^s: s = log2(det) / 2.
  return static_cast<int>(std::lround(0.5 * std::log2(det)));
}

}  // namespace livod::estimator::vio

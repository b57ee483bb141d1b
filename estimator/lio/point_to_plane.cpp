#include "estimator/lio/point_to_plane.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <thread>

#include "core/so3.hpp"

namespace livod::estimator {

PlaneRowJacobian point_to_plane_jacobian(const Plane& plane, const Eigen::Vector3d& p_imu,
                                         const State& x) {
  PlaneRowJacobian r;
  const Eigen::Vector3d& n = plane.normal;
  r.h = n.dot(x.R_world_imu * p_imu + x.p_world_imu) + plane.d;
  // [p]x R^T n, as a cross product (a 3x3 product per point otherwise).
  r.H.leftCols<3>() = p_imu.cross(x.R_world_imu.transpose() * n).transpose();
  r.H.rightCols<3>() = n.transpose();
  return r;
}

PointToPlane::PointToPlane(const VoxelMap& map, const Eigen::Isometry3d& T_imu_lidar, int threads)
    : map_(map), T_imu_lidar_(T_imu_lidar), threads_(std::max(1, threads)) {}

bool PointToPlane::linearize(const std::vector<ScanPoint>& points, const State& x,
                             NormalEquations& eq, int min_matches) {
  rows_.resize(points.size());
  hints_.resize(points.size());
  const Eigen::Matrix3d R = x.R_world_imu;
  const Eigen::Matrix3d R_wl = R * T_imu_lidar_.linear();
  auto work = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      Row& row = rows_[i];
      row.matched = false;
      const Eigen::Vector3d p_i = T_imu_lidar_ * points[i].p_lidar;
      const Eigen::Vector3d p_w = R * p_i + x.p_world_imu;
      const Eigen::Matrix3d cov_w = R_wl * points[i].cov_lidar * R_wl.transpose();
      PlaneMatch m;
      if (!map_.match(p_w, cov_w, m, hints_[i])) continue;
      const PlaneRowJacobian j = point_to_plane_jacobian(*m.plane, p_i, x);
      row.matched = true;
      row.H = j.H;
      row.z = -j.h;
      row.weight = 1.0 / (m.variance + 1e-6);
    }
  };
  const std::size_t n = points.size();
  if (threads_ <= 1 || n < 2000) {
    work(0, n);
  } else {
    std::vector<std::thread> pool;
    const std::size_t chunk =
        (n + static_cast<std::size_t>(threads_) - 1) / static_cast<std::size_t>(threads_);
    for (int t = 1; t < threads_; ++t) {
      const std::size_t b = static_cast<std::size_t>(t) * chunk;
      pool.emplace_back(work, std::min(b, n), std::min(b + chunk, n));
    }
    work(0, std::min(chunk, n));
    for (auto& th : pool) th.join();
  }
  // Deterministic sum in point order.
  Eigen::Matrix<double, 6, 6> HtH = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> Htz = Eigen::Matrix<double, 6, 1>::Zero();
  stats_ = PointToPlaneStats{};
  stats_.points = static_cast<int>(n);
  double abs_sum = 0.0;
  for (const Row& row : rows_) {
    if (!row.matched) continue;
    ++stats_.matched;
    HtH.noalias() += row.weight * row.H.transpose() * row.H;
    Htz.noalias() += row.weight * row.H.transpose() * row.z;
    eq.weighted_sq_residual += row.weight * row.z * row.z;
    abs_sum += std::abs(row.z);
  }
  stats_.mean_abs_residual_m = stats_.matched > 0 ? abs_sum / stats_.matched : 0.0;
  eq.HtRinvH.block<6, 6>(kRot, kRot) += HtH;
  eq.HtRinvz.segment<6>(kRot) += Htz;
  eq.measurements += stats_.matched;
  return stats_.matched >= min_matches;
}

DegeneracyReport assess_degeneracy(const StateMatrix& information, double min_ratio) {
  DegeneracyReport r;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> trans(information.block<3, 3>(kPos, kPos));
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> rot(information.block<3, 3>(kRot, kRot));
  r.translation_eigenvalues = trans.eigenvalues();
  r.rotation_eigenvalues = rot.eigenvalues();
  r.weakest_translation = trans.eigenvectors().col(0);
  const double largest = r.translation_eigenvalues(2);
  r.translation_ratio = largest > 0.0 ? r.translation_eigenvalues(0) / largest : 0.0;
  r.degenerate = r.translation_ratio < min_ratio;
  return r;
}

}  // namespace livod::estimator

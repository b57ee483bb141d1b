#include "estimator/lio/point_to_plane.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/so3.hpp"

namespace livod::estimator {

PlaneRowJacobian point_to_plane_jacobian(const Eigen::Vector3d& n, double d,
                                         const Eigen::Vector3d& p_imu, const State& x) {
  PlaneRowJacobian r;
  r.h = n.dot(x.R_world_imu * p_imu + x.p_world_imu) + d;
  // [p]x R^T n, as a cross product (a 3x3 product per point otherwise).
  r.H.leftCols<3>() = p_imu.cross(x.R_world_imu.transpose() * n).transpose();
  r.H.rightCols<3>() = n.transpose();
  return r;
}

PointToPlane::PointToPlane(const VoxelMap& map, const Eigen::Isometry3d& T_imu_lidar,
                           TaskRunner* runner, const PointNoise& noise, bool incidence)
    : PointToPlane(map, std::vector<Eigen::Isometry3d>{T_imu_lidar}, runner, noise, incidence) {}

PointToPlane::PointToPlane(const VoxelMap& map, std::vector<Eigen::Isometry3d> T_imu_lidars,
                           TaskRunner* runner, const PointNoise& noise, bool incidence)
    : map_(map), T_imu_lidars_(std::move(T_imu_lidars)), runner_(runner), incidence_(incidence) {
  if (T_imu_lidars_.empty() || T_imu_lidars_.size() > kMaxLidars) {
    throw std::invalid_argument("PointToPlane: between 1 and " + std::to_string(kMaxLidars) +
                                " LiDAR extrinsics");
  }
  noise_.fill(noise);
}

void PointToPlane::set_lidar_noise(std::size_t lidar, const PointNoise& noise) {
  if (lidar >= T_imu_lidars_.size()) {
    throw std::invalid_argument("PointToPlane: no LiDAR " + std::to_string(lidar));
  }
  noise_[lidar] = noise;
}

void PointToPlane::linearize_block(const std::vector<ScanPoint>& points, const State& x,
                                   std::size_t begin, std::size_t end, Block& block) {
  // Lookups run ahead of the matching: the table slot kSlotAhead points ahead, the node
  // kNodeAhead points ahead (VoxelMap::prefetch_root / resolve).
  constexpr std::size_t kSlotAhead = 16;
  constexpr std::size_t kNodeAhead = 8;
  const Eigen::Matrix3d& R = x.R_world_imu;
  // Each LiDAR's pose in the world at x (one with a single LiDAR).
  const std::size_t lidars = T_imu_lidars_.size();
  Eigen::Matrix3d R_wl[kMaxLidars];
  Eigen::Vector3d t_wl[kMaxLidars];
  for (std::size_t l = 0; l < lidars; ++l) {
    R_wl[l] = R * T_imu_lidars_[l].linear();
    t_wl[l] = R * T_imu_lidars_[l].translation() + x.p_world_imu;
  }
  double max_tan2[kMaxLidars];
  for (std::size_t l = 0; l < lidars; ++l) {
    max_tan2[l] = std::pow(std::tan(noise_[l].max_incidence_rad), 2);
  }
  const auto world = [&](std::size_t i) -> Eigen::Vector3d {
    const std::uint32_t l = points[i].lidar;
    return R_wl[l] * points[i].p_lidar + t_wl[l];
  };
  block.HtH.setZero();
  block.Htz.setZero();
  block.weighted_sq_residual = 0.0;
  block.abs_residual_sum = 0.0;
  block.matched = 0;
  for (std::size_t i = begin; i < std::min(end, begin + kNodeAhead); ++i) {
    map_.resolve(world(i), hints_[i]);
  }
  for (std::size_t i = begin; i < end; ++i) {
    if (i + kSlotAhead < end && !map_.is_current(hints_[i + kSlotAhead])) {
      map_.prefetch_root(world(i + kSlotAhead));
    }
    if (i + kNodeAhead < end) map_.resolve(world(i + kNodeAhead), hints_[i + kNodeAhead]);
    const Eigen::Vector3d& p_l = points[i].p_lidar;
    const std::uint32_t l = points[i].lidar;
    const Eigen::Vector3d p_i = T_imu_lidars_[l] * p_l;
    PointQuery q;
    q.p = R * p_i + x.p_world_imu;
    q.cov = R_wl[l] * points[i].cov_lidar * R_wl[l].transpose();
    q.gate_sigmas = gate_sigmas_[l];
    const PointNoise& own = noise_[l];  // the point's own LiDAR's
    const bool growth = own.range_limit_m > 0.0 && own.sigma_at_limit_m > 0.0;
    if (incidence_ || growth) {
      // The ray from the point's own LiDAR.
      const double r = p_l.norm();
      if (r > 0.0) {
        q.ray = R_wl[l] * (p_l / r);
        q.max_tan2 = max_tan2[l];
        if (incidence_) {
          q.incidence_var = r * r * own.bearing_sigma_rad * own.bearing_sigma_rad;
        }
        if (growth) {
          q.range_q2 = (r / own.range_limit_m) * (r / own.range_limit_m);
          q.var_at_limit = own.sigma_at_limit_m * own.sigma_at_limit_m;
        }
      }
    }
    normals_[i].setZero();
    PlaneMatch m;
    if (!map_.match(q, m, hints_[i])) continue;
    normals_[i] = m.plane->normal;
    const PlaneRowJacobian j = point_to_plane_jacobian(m.plane->normal, m.plane->d, p_i, x);
    const double w = 1.0 / (m.variance + 1e-6);
    const double z = -j.h;
    block.HtH.noalias() += w * j.H.transpose() * j.H;
    block.Htz.noalias() += (w * z) * j.H.transpose();
    block.weighted_sq_residual += w * z * z;
    block.abs_residual_sum += std::abs(z);
    ++block.matched;
  }
}

void PointToPlane::set_lidar_gate(std::size_t lidar, double sigmas) {
  if (lidar >= T_imu_lidars_.size()) {
    throw std::invalid_argument("PointToPlane: no LiDAR " + std::to_string(lidar));
  }
  if (!(sigmas > 0.0)) throw std::invalid_argument("PointToPlane: a gate must be positive");
  gate_sigmas_[lidar] = sigmas;
}

bool PointToPlane::linearize(const std::vector<ScanPoint>& points, const State& x,
                             NormalEquations& eq, int min_matches) {
  const std::size_t n = points.size();
  hints_.resize(n);
  normals_.resize(n);
  const std::size_t blocks = (n + kBlockPoints - 1) / kBlockPoints;
  blocks_.resize(blocks);
  const auto block_task = [&](std::size_t b) {
    linearize_block(points, x, b * kBlockPoints, std::min(n, (b + 1) * kBlockPoints), blocks_[b]);
  };
  if (runner_ != nullptr) {
    runner_->run(blocks, block_task);
  } else {
    for (std::size_t b = 0; b < blocks; ++b) block_task(b);
  }
  // Deterministic sum in block order.
  Eigen::Matrix<double, 6, 6> HtH = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> Htz = Eigen::Matrix<double, 6, 1>::Zero();
  stats_ = PointToPlaneStats{};
  stats_.points = static_cast<int>(n);
  double abs_sum = 0.0;
  for (const Block& block : blocks_) {
    HtH += block.HtH;
    Htz += block.Htz;
    eq.weighted_sq_residual += block.weighted_sq_residual;
    abs_sum += block.abs_residual_sum;
    stats_.matched += block.matched;
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

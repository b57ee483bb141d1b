#pragma once
// Point-to-plane measurements of a scan against the voxel map (fast-livo2-notes.md 1.3), as
// normal equations for the iterated update. Per point p_l (LiDAR frame, undistorted to the update
// time):
//   p_i = T_imu_lidar p_l,  p_w = R p_i + t
//   prediction h = n^T p_w + d,  measurement 0  ->  z = -(n^T p_w + d)
//   H = [ ([p_i]x R^T n)^T , n^T , 0 ... ]     (rotation block, position block)
//   weight 1 / (var_plane + n^T S_w n),  S_w = R R_il S_l R_il^T R^T   (FAST-LIVO2 defect 8:
//   it forgets R_il here)
// Association is redone at every iteration. Residuals are computed in parallel (TaskRunner) into a
// per-point array and summed in point order, so the result does not depend on the thread count.

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

#include "estimator/filter/esikf.hpp"
#include "estimator/lidars.hpp"
#include "estimator/map/point_covariance.hpp"
#include "estimator/map/voxel_map.hpp"
#include "estimator/task_runner.hpp"

namespace livod::estimator {

struct ScanPoint {
  Eigen::Vector3d p_lidar = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cov_lidar = Eigen::Matrix3d::Zero();
  std::uint32_t lidar = 0;  // which LiDAR measured it: index into the T_imu_lidar list
};

// Prediction h = n^T (R p_imu + t) + d of one point against the plane n^T x + d = 0, and its
// Jacobian with
// respect to the (rotation, position) error state.
struct PlaneRowJacobian {
  double h = 0.0;
  Eigen::Matrix<double, 1, 6> H;
};
PlaneRowJacobian point_to_plane_jacobian(const Eigen::Vector3d& normal, double d,
                                         const Eigen::Vector3d& p_imu, const State& x);

struct PointToPlaneStats {
  int points = 0;
  int matched = 0;
  double mean_abs_residual_m = 0.0;
};

class PointToPlane {
 public:
  // `runner` (nullptr: the caller's thread) must outlive this object. `incidence`: add the
  // incidence-angle term of `noise` to each point's variance along the candidate plane's normal.
  PointToPlane(const VoxelMap& map, const Eigen::Isometry3d& T_imu_lidar, TaskRunner* runner,
               const PointNoise& noise = {}, bool incidence = false);
  // Several LiDARs: ScanPoint::lidar indexes `T_imu_lidars` (each point in its own LiDAR's frame).
  PointToPlane(const VoxelMap& map, std::vector<Eigen::Isometry3d> T_imu_lidars, TaskRunner* runner,
               const PointNoise& noise = {}, bool incidence = false);

  // Several LiDARs: the noise model of one LiDAR's points (its incidence term), when it differs
  // from the constructor's.
  void set_lidar_noise(std::size_t lidar, const PointNoise& noise);
  // The association gate (in sigmas) of LiDAR `lidar`'s rows instead of the map's sigma_num.
  void set_lidar_gate(std::size_t lidar, double sigmas);

  // Accumulates the normal equations of every matched point at state x.
  bool linearize(const std::vector<ScanPoint>& points, const State& x, NormalEquations& eq,
                 int min_matches);

  [[nodiscard]] const PointToPlaneStats& stats() const { return stats_; }
  // World normal of the plane each point matched at the last linearize() (zero: no match); the
  // map insertion uses it for the points' incidence term.
  [[nodiscard]] const std::vector<Eigen::Vector3d>& matched_normals() const { return normals_; }

 private:
  // Normal equations of one block of points. Blocks have a fixed size, are filled in any order
  // on any thread and summed in block order: the total does not depend on the thread count.
  struct Block {
    Eigen::Matrix<double, 6, 6> HtH = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> Htz = Eigen::Matrix<double, 6, 1>::Zero();
    double weighted_sq_residual = 0.0;
    double abs_residual_sum = 0.0;
    int matched = 0;
  };
  static constexpr std::size_t kBlockPoints = 512;
  void linearize_block(const std::vector<ScanPoint>& points, const State& x, std::size_t begin,
                       std::size_t end, Block& block);

  const VoxelMap& map_;
  std::vector<Eigen::Isometry3d> T_imu_lidars_;
  TaskRunner* runner_;
  std::array<PointNoise, kMaxLidars> noise_;      // per LiDAR
  std::array<double, kMaxLidars> gate_sigmas_{};  // per LiDAR; 0: the map's sigma_num
  bool incidence_;
  std::vector<Eigen::Vector3d> normals_;
  std::vector<Block> blocks_;
  std::vector<VoxelMap::Hint> hints_;  // per point, reused over the iterations of one update
  PointToPlaneStats stats_;
};

// Degeneracy of the LiDAR constraints from the pose block of H^T R^-1 H: the eigenvalues of the
// translation and rotation information, and the weakest translation direction (world frame).
struct DegeneracyReport {
  Eigen::Vector3d translation_eigenvalues = Eigen::Vector3d::Zero();  // ascending
  Eigen::Vector3d rotation_eigenvalues = Eigen::Vector3d::Zero();
  Eigen::Vector3d weakest_translation = Eigen::Vector3d::Zero();
  double translation_ratio = 0.0;  // smallest / largest translation eigenvalue
  bool degenerate = false;
};
DegeneracyReport assess_degeneracy(const StateMatrix& information, double min_ratio);

}  // namespace livod::estimator

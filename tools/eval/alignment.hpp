#pragma once
// Least-squares alignment of an estimated trajectory onto ground truth (Umeyama 1991,
// "Least-squares estimation of transformation parameters between two point patterns"):
// find s, R, t minimising Σ |gt_i − (s·R·est_i + t)|² over the associated positions.
// SE(3) fixes s = 1; Sim(3) also estimates the scale (monocular estimates).

#include <Eigen/Core>
#include <optional>
#include <string_view>
#include <vector>

#include "core/se3.hpp"
#include "tools/eval/trajectory.hpp"

namespace livod::eval {

enum class Alignment { kNone, kSe3, kSim3 };

std::optional<Alignment> parse_alignment(std::string_view name);  // "none" | "se3" | "sim3"
std::string_view to_string(Alignment alignment);

// x_gt = scale · R · x_est + t
struct Similarity3 {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  double scale = 1.0;

  // Applied to a pose of the estimate: position scaled then moved, orientation rotated.
  [[nodiscard]] RigidTransform3d apply(const RigidTransform3d& T_world_body) const {
    return {rotation * T_world_body.rotation,
            scale * (rotation * T_world_body.translation) + translation};
  }
};

// Umeyama on point pairs (same length, at least 3 for a unique rotation). Throws livod::Error
// when fewer than 2 points are given or the estimate's points are all identical.
Similarity3 umeyama(const std::vector<Eigen::Vector3d>& est, const std::vector<Eigen::Vector3d>& gt,
                    bool with_scale);

// Alignment of two associated trajectories of equal length (identity for kNone).
Similarity3 align(const Trajectory& gt, const Trajectory& est, Alignment alignment);

Trajectory transformed(const Trajectory& traj, const Similarity3& sim);

}  // namespace livod::eval

#pragma once
// A trajectory as the evaluation sees it: poses T_world_body, optionally stamped. KITTI files
// carry no time (stamps stay empty unless a times file is given); TUM and EuRoC files do.

#include <cstddef>
#include <vector>

#include "core/se3.hpp"

namespace livod::eval {

struct Trajectory {
  std::vector<double> stamps_s;         // seconds, same length as poses, or empty
  std::vector<RigidTransform3d> poses;  // T_world_body, x_world = T * x_body

  [[nodiscard]] std::size_t size() const { return poses.size(); }
  [[nodiscard]] bool empty() const { return poses.empty(); }
  [[nodiscard]] bool has_stamps() const { return !stamps_s.empty(); }

  // Sum of the distances between consecutive positions (metres).
  [[nodiscard]] double path_length() const;

  // The poses (and stamps) at the given indices, in that order.
  [[nodiscard]] Trajectory subset(const std::vector<std::size_t>& indices) const;
};

}  // namespace livod::eval

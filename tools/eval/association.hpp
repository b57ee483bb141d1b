#pragma once
// Pairing estimate poses with ground-truth poses.
//
// By time (evo's associate_trajectories): the estimate's stamps are shifted by `offset_s`
// (t_est + offset ≈ t_gt). Every stamp of the trajectory with fewer poses is matched to the
// nearest stamp of the other one; the pair is kept if the difference is at most `max_diff_s`.
// Ties go to the earlier pose. A pose of the longer trajectory may be used more than once.
//
// By index (KITTI): pose i with pose i; both trajectories must have the same length.

#include <cstddef>
#include <vector>

#include "tools/eval/trajectory.hpp"

namespace livod::eval {

struct Association {
  std::vector<std::size_t> gt_index;
  std::vector<std::size_t> est_index;

  [[nodiscard]] std::size_t size() const { return gt_index.size(); }
};

// Throws livod::Error when either trajectory lacks stamps or nothing matches.
Association associate_by_time(const Trajectory& gt, const Trajectory& est, double max_diff_s,
                              double offset_s);

// Throws livod::Error when the lengths differ or the trajectories are empty.
Association associate_by_index(const Trajectory& gt, const Trajectory& est);

}  // namespace livod::eval

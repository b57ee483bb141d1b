#include "tools/eval/association.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.hpp"

namespace livod::eval {
namespace {

// For each stamp of `query`, the index of the nearest `target` stamp (target + shift), if it is
// within max_diff. `target` is sorted, so a binary search replaces evo's full argmin scan; the
// first of equally near candidates wins, as with argmin.
void match_nearest(const std::vector<double>& query, const std::vector<double>& target,
                   double max_diff, double shift, std::vector<std::size_t>& query_index,
                   std::vector<std::size_t>& target_index) {
  for (std::size_t i = 0; i < query.size(); ++i) {
    const double t = query[i] - shift;
    auto it = std::lower_bound(target.begin(), target.end(), t);
    std::size_t best = 0;
    if (it == target.end()) {
      best = target.size() - 1;
    } else {
      best = static_cast<std::size_t>(it - target.begin());
      if (best > 0) {
        const double d_before = std::abs(target[best - 1] + shift - query[i]);
        const double d_after = std::abs(target[best] + shift - query[i]);
        if (d_before <= d_after) best -= 1;
      }
    }
    // Repeated stamps: argmin returns the first of the run.
    while (best > 0 && target[best - 1] == target[best]) --best;
    if (std::abs(target[best] + shift - query[i]) <= max_diff) {
      query_index.push_back(i);
      target_index.push_back(best);
    }
  }
}

}  // namespace

Association associate_by_time(const Trajectory& gt, const Trajectory& est, double max_diff_s,
                              double offset_s) {
  if (!gt.has_stamps() || !est.has_stamps()) {
    throw Error("time association needs timestamps in both trajectories");
  }
  if (gt.empty() || est.empty()) throw Error("cannot associate an empty trajectory");
  Association a;
  if (est.size() > gt.size()) {
    // Iterate ground truth; the estimate (shifted by +offset) is the target.
    match_nearest(gt.stamps_s, est.stamps_s, max_diff_s, offset_s, a.gt_index, a.est_index);
  } else {
    // Iterate the estimate; ground truth is shifted by −offset relative to it.
    match_nearest(est.stamps_s, gt.stamps_s, max_diff_s, -offset_s, a.est_index, a.gt_index);
  }
  if (a.size() == 0) {
    throw Error("no matching timestamps between ground truth and estimate (max difference " +
                std::to_string(max_diff_s) + " s, offset " + std::to_string(offset_s) + " s)");
  }
  return a;
}

Association associate_by_index(const Trajectory& gt, const Trajectory& est) {
  if (gt.size() != est.size()) {
    throw Error("index association needs trajectories of equal length (ground truth " +
                std::to_string(gt.size()) + " poses, estimate " + std::to_string(est.size()) + ")");
  }
  if (gt.empty()) throw Error("cannot associate an empty trajectory");
  Association a;
  a.gt_index.resize(gt.size());
  a.est_index.resize(est.size());
  for (std::size_t i = 0; i < gt.size(); ++i) a.gt_index[i] = a.est_index[i] = i;
  return a;
}

}  // namespace livod::eval

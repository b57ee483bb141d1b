#include "tests/runtime/pose_comparison.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "core/so3.hpp"

namespace livod::test {

using daemon::publish::PoseRecord;
using daemon::publish::PoseStatus;

PoseComparison compare_with_replay(const std::vector<PoseRecord>& live,
                                   const eval::Trajectory& replayed) {
  PoseComparison best;
  if (live.empty() || replayed.stamps_s.empty()) return best;
  std::vector<std::int64_t> rep_ns;
  rep_ns.reserve(replayed.stamps_s.size());
  for (const double t : replayed.stamps_s) rep_ns.push_back(std::llround(t * 1e9));
  // The first live pose is one of the replay's first few (the live run may miss the first scan).
  for (std::size_t j = 0; j < std::min<std::size_t>(8, rep_ns.size()); ++j) {
    const std::int64_t shift = live.front().t.ns - rep_ns[j];
    PoseComparison c;
    c.shift_ns = shift;
    for (const auto& p : live) {
      if (p.status == PoseStatus::kSensorStale) continue;
      const std::int64_t t = p.t.ns - shift;
      const auto it = std::lower_bound(rep_ns.begin(), rep_ns.end(), t - 1'000'000);
      if (it == rep_ns.end() || std::llabs(*it - t) > 1'000'000) continue;
      const auto k = static_cast<std::size_t>(it - rep_ns.begin());
      ++c.matched;
      const double dp = (p.p_world_body - replayed.poses[k].translation).norm();
      if (std::getenv("LIVOD_TEST_VERBOSE") != nullptr) {
        std::printf("pose %zu t %.3f dp %.3f mm\n", k,
                    static_cast<double>(t - rep_ns.front()) * 1e-9, dp * 1e3);
      }
      c.max_position_m = std::max(c.max_position_m, dp);
      const Eigen::Matrix3d dR = replayed.poses[k].rotation.transpose() * p.R_world_body;
      c.max_rotation_deg = std::max(c.max_rotation_deg, so3::log(dR).norm() * 180.0 / M_PI);
    }
    if (c.matched > best.matched) best = c;
  }
  return best;
}

std::size_t real_poses(const std::vector<PoseRecord>& poses) {
  return static_cast<std::size_t>(std::count_if(poses.begin(), poses.end(), [](const auto& p) {
    return p.status != PoseStatus::kSensorStale;
  }));
}

}  // namespace livod::test

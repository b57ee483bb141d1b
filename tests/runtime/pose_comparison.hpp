#pragma once
// Live poses against `livod replay`'s trajectory of the same capture, for the daemon's tests. Both
// timelines are the sensor's clock plus a constant (live: the host's monotonic clock the capture
// was mapped onto; replay: the recording's); the constant is the one that pairs most poses within
// 1 ms. SENSOR_STALE poses are repeats of the last pose, not new ones, and are not paired.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "daemon/publish/records.hpp"
#include "tools/eval/trajectory.hpp"

namespace livod::test {

struct PoseComparison {
  std::size_t matched = 0;
  double max_position_m = 0.0;
  double max_rotation_deg = 0.0;
  std::int64_t shift_ns = 0;  // live time - replay time of the paired poses
};

PoseComparison compare_with_replay(const std::vector<daemon::publish::PoseRecord>& live,
                                   const eval::Trajectory& replayed);

// Poses that are filter updates (not SENSOR_STALE repeats).
std::size_t real_poses(const std::vector<daemon::publish::PoseRecord>& poses);

}  // namespace livod::test

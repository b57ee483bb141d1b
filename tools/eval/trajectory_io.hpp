#pragma once
// Trajectory file readers for evaluation.
//   TUM:   `t tx ty tz qx qy qz qw` per line, t in seconds, '#' comments. The quaternion is
//          normalised (a zero quaternion is an error).
//   KITTI: 12 numbers per line, the row-major 3x4 matrix [R | t] of T_world_cam. No time: poses
//          are matched by index; a times file (one time in seconds per line, as KITTI's
//          times.txt) can stamp them. Rotations are used as read (no re-orthonormalisation,
//          like evo), so that results match evo's on KITTI's 7-digit matrices.
//   EuRoC: ASL ground-truth csv `#timestamp [ns], p_RS_R_x, _y, _z, q_RS_w, _x, _y, _z, ...`
//          (further columns such as velocity and biases are ignored).
// Malformed input raises livod::FormatError carrying the byte offset of the bad line or field and
// "line N" in the message. Timestamps must not decrease.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tools/eval/trajectory.hpp"

namespace livod::eval {

enum class TrajectoryFormat {
  kTum,    // both files TUM
  kKitti,  // both files KITTI
  kEuroc,  // ground truth EuRoC csv, estimate TUM (evo's `euroc` mode)
};

std::optional<TrajectoryFormat> parse_trajectory_format(std::string_view name);
std::string_view to_string(TrajectoryFormat format);

// Parsers over file contents; `source` names the input in error messages.
Trajectory parse_tum(std::string_view text, const std::string& source);
Trajectory parse_kitti(std::string_view text, const std::string& source);
Trajectory parse_euroc_csv(std::string_view text, const std::string& source);
std::vector<double> parse_times(std::string_view text, const std::string& source);

Trajectory read_tum(const std::filesystem::path& path);
Trajectory read_euroc_csv(const std::filesystem::path& path);
// With `times`, the trajectory is stamped; the times file must have one line per pose.
Trajectory read_kitti(const std::filesystem::path& path,
                      const std::optional<std::filesystem::path>& times = std::nullopt);

}  // namespace livod::eval

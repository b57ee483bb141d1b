#pragma once
// OUTDIR/trajectory.txt: one TUM line per estimator frame, `t tx ty tz qx qy qz qw`, the pose of
// the body (IMU) frame in the estimator's world frame at the frame's measurement time. Times are
// printed from the integer mapped nanoseconds (never through a double: 1.7e9 s in a double only
// resolves 0.24 us), so equal inputs give equal bytes. The file is written as NAME.partial and
// renamed by close() (io/output_file.hpp): an interrupted run never leaves a truncated NAME.

#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <string>

#include "core/time.hpp"
#include "io/output_file.hpp"

namespace livod::daemon::replay {

// "1700000000.123456789" for 1700000000123456789 ns (exact, nine decimals, sign kept).
std::string format_seconds(std::int64_t ns);

class TrajectoryWriter {
 public:
  // Throws livod::Error if the file cannot be created.
  explicit TrajectoryWriter(const std::filesystem::path& path);
  TrajectoryWriter(TrajectoryWriter&&) = delete;
  void write(MappedTime t, const Eigen::Matrix3d& R_world_body,
             const Eigen::Vector3d& p_world_body);
  // Throws livod::Error if the data could not be written.
  void close();
  [[nodiscard]] std::size_t poses() const { return poses_; }

 private:
  io::OutputFile file_;
  std::size_t poses_ = 0;
};

}  // namespace livod::daemon::replay

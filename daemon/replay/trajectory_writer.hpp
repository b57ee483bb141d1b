#pragma once
// OUTDIR/trajectory.txt: one TUM line per estimator frame, `t tx ty tz qx qy qz qw`, the pose of
// the body (IMU) frame in the estimator's world frame at the frame's measurement time, written
// by io::TumWriter (exact nanosecond times, fixed quaternion sign: equal inputs give equal
// bytes; written as NAME.partial and renamed by close(), so an interrupted run never leaves a
// truncated NAME).

#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <string>

#include "core/time.hpp"
#include "io/tum_writer.hpp"

namespace livod::daemon::replay {

using io::format_seconds;

class TrajectoryWriter {
 public:
  // Throws livod::Error if the file cannot be created.
  explicit TrajectoryWriter(const std::filesystem::path& path) : writer_(path) {}
  TrajectoryWriter(TrajectoryWriter&&) = delete;
  void write(MappedTime t, const Eigen::Matrix3d& R_world_body,
             const Eigen::Vector3d& p_world_body) {
    writer_.write(t.ns, R_world_body, p_world_body);
  }
  // Throws livod::Error if the data could not be written.
  void close() { writer_.close(); }
  [[nodiscard]] std::size_t poses() const { return writer_.poses(); }

 private:
  io::TumWriter writer_;
};

}  // namespace livod::daemon::replay

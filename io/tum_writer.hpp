#pragma once
// TUM trajectory files: one line per pose, `t tx ty tz qx qy qz qw`, t in seconds. Times are
// printed from integer nanoseconds (never through a double: 1.7e9 s in a double only resolves
// 0.24 us), and the quaternion sign is fixed (w >= 0, TUM leaves it free) so that equal poses
// give equal bytes. The file is written as NAME.partial and renamed by close()
// (io/output_file.hpp): an interrupted run never leaves a truncated NAME. Used by `livod replay`
// (trajectory.txt) and `livod sim` (groundtruth.txt).

#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <string>

#include "io/output_file.hpp"

namespace livod::io {

// "1700000000.123456789" for 1700000000123456789 ns (exact, nine decimals, sign kept).
[[nodiscard]] std::string format_seconds(std::int64_t ns);

// One TUM line (with its newline) for the pose (R_world_body, p_world_body) at t_ns.
[[nodiscard]] std::string tum_line(std::int64_t t_ns, const Eigen::Matrix3d& R_world_body,
                                   const Eigen::Vector3d& p_world_body);

class TumWriter {
 public:
  // Throws livod::Error if the file cannot be created. A non-empty `comment` is written first as
  // "# comment".
  explicit TumWriter(const std::filesystem::path& path, const std::string& comment = {});
  TumWriter(TumWriter&&) = delete;
  void write(std::int64_t t_ns, const Eigen::Matrix3d& R_world_body,
             const Eigen::Vector3d& p_world_body);
  // Throws livod::Error if the data could not be written.
  void close();
  [[nodiscard]] std::size_t poses() const { return poses_; }

 private:
  OutputFile file_;
  std::size_t poses_ = 0;
};

}  // namespace livod::io

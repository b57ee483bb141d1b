#include "daemon/replay/trajectory_writer.hpp"

#include <fmt/core.h>

namespace livod::daemon::replay {

std::string format_seconds(std::int64_t ns) {
  constexpr std::int64_t kNsPerSecond = 1'000'000'000;
  const bool negative = ns < 0;
  // Work on the magnitude as unsigned so that INT64_MIN does not overflow.
  const std::uint64_t magnitude =
      negative ? ~static_cast<std::uint64_t>(ns) + 1 : static_cast<std::uint64_t>(ns);
  return fmt::format("{}{}.{:09d}", negative ? "-" : "", magnitude / kNsPerSecond,
                     magnitude % kNsPerSecond);
}

TrajectoryWriter::TrajectoryWriter(const std::filesystem::path& path) : file_(path) {}

void TrajectoryWriter::write(MappedTime t, const Eigen::Matrix3d& R_world_body,
                             const Eigen::Vector3d& p_world_body) {
  Eigen::Quaterniond q(R_world_body);
  q.normalize();
  // TUM leaves the quaternion sign free; a fixed convention (w >= 0) keeps files comparable.
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  file_.stream() << fmt::format("{} {:.9f} {:.9f} {:.9f} {:.9f} {:.9f} {:.9f} {:.9f}\n",
                                format_seconds(t.ns), p_world_body.x(), p_world_body.y(),
                                p_world_body.z(), q.x(), q.y(), q.z(), q.w());
  ++poses_;
}

void TrajectoryWriter::close() {
  file_.commit();
}

}  // namespace livod::daemon::replay

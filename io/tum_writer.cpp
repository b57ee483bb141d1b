#include "io/tum_writer.hpp"

#include <cinttypes>
#include <cstdio>

#include "core/time.hpp"

namespace livod::io {

std::string format_seconds(std::int64_t ns) {
  constexpr auto kNsPerSecondUnsigned = static_cast<std::uint64_t>(kNsPerSecond);
  const bool negative = ns < 0;
  // Work on the magnitude as unsigned so that INT64_MIN does not overflow.
  const std::uint64_t magnitude =
      negative ? ~static_cast<std::uint64_t>(ns) + 1 : static_cast<std::uint64_t>(ns);
  char text[40];
  std::snprintf(text, sizeof text, "%s%" PRIu64 ".%09" PRIu64, negative ? "-" : "",
                magnitude / kNsPerSecondUnsigned, magnitude % kNsPerSecondUnsigned);
  return text;
}

std::string tum_line(std::int64_t t_ns, const Eigen::Matrix3d& R_world_body,
                     const Eigen::Vector3d& p_world_body) {
  Eigen::Quaterniond q(R_world_body);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  char pose[192];
  std::snprintf(pose, sizeof pose, " %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", p_world_body.x(),
                p_world_body.y(), p_world_body.z(), q.x(), q.y(), q.z(), q.w());
  return format_seconds(t_ns) + pose;
}

TumWriter::TumWriter(const std::filesystem::path& path, const std::string& comment) : file_(path) {
  if (!comment.empty()) file_.stream() << "# " << comment << '\n';
}

void TumWriter::write(std::int64_t t_ns, const Eigen::Matrix3d& R_world_body,
                      const Eigen::Vector3d& p_world_body) {
  file_.stream() << tum_line(t_ns, R_world_body, p_world_body);
  ++poses_;
}

void TumWriter::close() {
  file_.commit();
}

}  // namespace livod::io

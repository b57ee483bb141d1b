#include "io/rosbag/ros_serialization.hpp"

#include <limits>

#include "core/time.hpp"

namespace livod::io::rosbag {

RosTime RosTime::from_ns(std::int64_t ns) {
  if (ns < 0 || ns / kNsPerSecond > std::numeric_limits<std::uint32_t>::max()) {
    throw Error("ROS time out of range (needs 0 <= t < 2^32 s): " + std::to_string(ns) + " ns");
  }
  RosTime t;
  t.sec = static_cast<std::uint32_t>(ns / kNsPerSecond);
  t.nsec = static_cast<std::uint32_t>(ns % kNsPerSecond);
  return t;
}

void RosWriter::write_count(std::size_t n) {
  if (n > std::numeric_limits<std::uint32_t>::max()) {
    throw Error("ROS serialization: length " + std::to_string(n) + " does not fit in u32");
  }
  write(static_cast<std::uint32_t>(n));
}

}  // namespace livod::io::rosbag

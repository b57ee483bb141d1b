// libFuzzer target: the ROS1 message deserializers, the PointCloud2 point extraction and the
// md5 computation over message definition text. The first byte picks the message type, the rest
// is the serialized message. A message that decodes must survive serialize -> deserialize ->
// serialize unchanged (the first serialize normalizes bools to 0/1); anything else than decoding
// or a livod::FormatError is a bug.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <string_view>
#include <type_traits>
#include <vector>

#include "core/error.hpp"
#include "io/rosbag/point_cloud.hpp"
#include "io/rosbag/ros_md5.hpp"
#include "io/rosbag/ros_messages.hpp"

namespace {

using namespace livod::io::rosbag;  // NOLINT: a fuzz driver, not a header

template <class Msg>
void round_trip(std::span<const std::byte> bytes) {
  Msg msg;
  try {
    deserialize(bytes, msg);
  } catch (const livod::FormatError&) {
    return;
  }
  const std::vector<std::byte> once = serialize(msg);
  const std::vector<std::byte> twice = serialize(deserialize<Msg>(once));
  if (once != twice) std::abort();
  if constexpr (std::is_same_v<Msg, sensor_msgs::PointCloud2>) {
    std::vector<CloudPoint> points;
    CloudFields fields;
    fields.time = msg.fields.empty() ? "t" : msg.fields.back().name;
    try {
      extract_points(msg, fields, points);
    } catch (const livod::FormatError&) {
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data) + 1, size - 1);
  switch (data[0] % 9) {
    case 0:
      round_trip<std_msgs::Header>(bytes);
      break;
    case 1:
      round_trip<std_msgs::String>(bytes);
      break;
    case 2:
      round_trip<sensor_msgs::Imu>(bytes);
      break;
    case 3:
      round_trip<sensor_msgs::PointCloud2>(bytes);
      break;
    case 4:
      round_trip<sensor_msgs::Image>(bytes);
      break;
    case 5:
      round_trip<sensor_msgs::CompressedImage>(bytes);
      break;
    case 6:
      round_trip<livox_ros_driver::CustomMsg>(bytes);
      break;
    case 7:
      round_trip<ouster_ros::PacketMsg>(bytes);
      break;
    default:
      try {
        (void)compute_ros_md5sum(
            "fuzz_msgs/Top",
            std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
      } catch (const livod::Error&) {
      }
      break;
  }
  return 0;
}

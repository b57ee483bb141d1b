// libFuzzer target: the ROS1 bag reader on an in-memory bag, strict and recovering. Any input
// must either open and read cleanly or raise livod::Error (FormatError); a crash, a sanitizer
// report or any other exception (bad_alloc from a trusted bogus length...) is a bug. Messages of
// the types livod knows are decoded too, and every connection's definition goes through the md5
// computation. Raw .bag files (e.g. shared/data/rosbag1) work as seeds as they are.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/error.hpp"
#include "io/rosbag/bag_reader.hpp"
#include "io/rosbag/ros_md5.hpp"

namespace {

using namespace livod::io::rosbag;  // NOLINT: a fuzz driver, not a header

// Bounded so that one input cannot run for long: a few MiB of chunk, a few thousand messages.
constexpr std::size_t kMaxChunkBytes = std::size_t{8} << 20;
constexpr int kMaxMessages = 4000;

void decode(const BagMessage& m) {
  const std::string& type = m.connection->type;
  try {
    if (type == MessageTraits<sensor_msgs::Imu>::type) {
      (void)deserialize<sensor_msgs::Imu>(m.data);
    } else if (type == MessageTraits<sensor_msgs::PointCloud2>::type) {
      (void)deserialize<sensor_msgs::PointCloud2>(m.data);
    } else if (type == MessageTraits<sensor_msgs::Image>::type) {
      (void)deserialize<sensor_msgs::Image>(m.data);
    } else if (type == MessageTraits<sensor_msgs::CompressedImage>::type) {
      (void)deserialize<sensor_msgs::CompressedImage>(m.data);
    } else if (type == MessageTraits<livox_ros_driver::CustomMsg>::type) {
      (void)deserialize<livox_ros_driver::CustomMsg>(m.data);
    } else if (type == MessageTraits<ouster_ros::PacketMsg>::type) {
      (void)deserialize<ouster_ros::PacketMsg>(m.data);
    } else if (type == MessageTraits<std_msgs::String>::type) {
      (void)deserialize<std_msgs::String>(m.data);
    }
  } catch (const livod::FormatError&) {
    // A message that does not decode is the message's problem, not the reader's.
  }
}

void exercise(const std::vector<std::byte>& bytes, bool recover) {
  BagReader::Options options;
  options.recover = recover;
  options.max_chunk_bytes = kMaxChunkBytes;
  try {
    const BagReader bag = BagReader::from_bytes(bytes, "fuzz", options);
    (void)bag.topics();
    (void)bag.message_count();
    for (const Connection& c : bag.connections()) {
      try {
        (void)compute_ros_md5sum(c.type, c.message_definition);
      } catch (const livod::Error&) {
      }
    }
    auto cursor = bag.read();
    int n = 0;
    while (n < kMaxMessages) {
      const auto m = cursor.next();
      if (!m) break;
      decode(*m);
      ++n;
    }
    // A time window and a topic filter take other paths through the index.
    const auto start = bag.start_time_ns();
    const auto end = bag.end_time_ns();
    if (start && end && !bag.connections().empty()) {
      BagQuery q;
      q.start_ns = *start + (*end - *start) / 2;
      q.end_ns = *end;
      q.topics = {bag.connections().front().topic};
      auto window = bag.read(q);
      for (int k = 0; k < kMaxMessages && window.next(); ++k) {
      }
    }
    (void)bag.chunk_compressions();
  } catch (const livod::Error&) {
    // FormatError (or Error) is the expected outcome for malformed input.
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::vector<std::byte> bytes(reinterpret_cast<const std::byte*>(data),
                                     reinterpret_cast<const std::byte*>(data) + size);
  exercise(bytes, false);
  exercise(bytes, true);
  return 0;
}

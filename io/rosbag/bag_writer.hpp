#pragma once
// ROS1 bag (format 2.0) writer, laid out as rosbag's C++ writer does so that rosbag play,
// FAST-LIO/FAST-LIVO2 and the rosbag Python/C++ readers accept the files:
//   magic, bag header record (padded to 4096 bytes, rewritten on close with index_pos and the
//   counts), chunks (a connection record before its first message, then message data records),
//   after each chunk one index data record per connection in it, and on close the index
//   section: every connection record, then one chunk info record per chunk.
// Header fields are written sorted by name, chunks close once their uncompressed size exceeds the
// threshold (768 KiB by default), compression none/bz2/lz4. No clock is read and no address is
// written, so the same writes give the same bytes.
//
//   BagWriter bag("out.bag", {.compression = Compression::kLz4});
//   const auto imu = bag.add_connection<sensor_msgs::Imu>("/imu/data");
//   bag.write(imu, t_ns, imu_msg);
//   bag.close();

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "io/rosbag/chunk_compression.hpp"
#include "io/rosbag/ros_messages.hpp"

namespace livod::io::rosbag {

struct ConnectionSpec {
  std::string topic;
  std::string type;                // "sensor_msgs/Imu"
  std::string md5sum;              // of the type
  std::string message_definition;  // full text (MessageTraits<T>::definition())
  std::string callerid;            // optional publisher node name ("" = not written)
  bool latching = false;           // written as latching=1 when true
};

class BagWriter {
 public:
  struct Options {
    Compression compression = Compression::kNone;
    // A chunk is closed once its uncompressed records exceed this (rosbag's default).
    std::size_t chunk_threshold = 768 * 1024;
  };

  // Creates (truncates) the file. Throws livod::Error if it cannot be opened.
  BagWriter(const std::filesystem::path& path, Options options);
  explicit BagWriter(const std::filesystem::path& path) : BagWriter(path, Options{}) {}
  // Closes the bag if close() was not called; errors there are lost, so call close().
  ~BagWriter();
  BagWriter(BagWriter&&) noexcept;
  BagWriter& operator=(BagWriter&&) noexcept;
  BagWriter(const BagWriter&) = delete;
  BagWriter& operator=(const BagWriter&) = delete;

  // Returns the connection id (0, 1, ... in order of creation).
  std::uint32_t add_connection(const ConnectionSpec& spec);

  template <class Msg>
  std::uint32_t add_connection(std::string topic) {
    ConnectionSpec spec;
    spec.topic = std::move(topic);
    spec.type = std::string(MessageTraits<Msg>::type);
    spec.md5sum = std::string(MessageTraits<Msg>::md5sum);
    spec.message_definition = std::string(MessageTraits<Msg>::definition());
    return add_connection(spec);
  }

  // Appends one serialized message. time_ns is the record time; rosbag rejects times below
  // 1 ns (ros::TIME_MIN) and the format stores u32 seconds, so 1 <= time_ns < 2^32 s, else
  // livod::Error. Messages need not be in time order (readers sort by the index).
  void write(std::uint32_t connection, std::int64_t time_ns, std::span<const std::byte> message);

  // Serializes and appends a message; throws livod::Error if the connection's type is not Msg's.
  template <class Msg>
  requires requires { MessageTraits<Msg>::type; }
  void write(std::uint32_t connection, std::int64_t time_ns, const Msg& msg) {
    check_type(connection, MessageTraits<Msg>::type);
    serialize(msg, scratch_);
    write(connection, time_ns, std::span<const std::byte>(scratch_));
  }

  // Flushes the open chunk, writes the index section and the final bag header. Idempotent.
  void close();

 private:
  void check_type(std::uint32_t connection, std::string_view type) const;

  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<std::byte> scratch_;
};

}  // namespace livod::io::rosbag

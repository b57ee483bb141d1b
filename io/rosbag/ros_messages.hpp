#pragma once
// Plain C++ mirrors of the ROS1 messages livod replays or writes, with ROS1 (de)serializers.
// Namespaces follow the ROS packages (rosbag::sensor_msgs::Imu is sensor_msgs/Imu). No OpenCV and
// no ROS: an Image is its encoding, size, step and bytes.
//
// deserialize() checks every length against the input and throws livod::FormatError (source =
// message type, offset inside the message) on truncated, inconsistent or over-long input.
// MessageTraits<T> gives the ROS type name, the md5sum and the full message_definition text that
// a bag connection record carries (the md5sums are the real ROS ones; ros_md5.hpp recomputes
// them from the definitions and the tests check both).

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "io/rosbag/ros_serialization.hpp"

namespace livod::io::rosbag {

namespace std_msgs {

struct Header {
  std::uint32_t seq = 0;
  RosTime stamp;
  std::string frame_id;
  friend bool operator==(const Header&, const Header&) = default;
};

struct String {
  std::string data;
  friend bool operator==(const String&, const String&) = default;
};

}  // namespace std_msgs

namespace geometry_msgs {

struct Vector3 {
  double x = 0;
  double y = 0;
  double z = 0;
  friend bool operator==(const Vector3&, const Vector3&) = default;
};

struct Quaternion {
  double x = 0;
  double y = 0;
  double z = 0;
  double w = 0;
  friend bool operator==(const Quaternion&, const Quaternion&) = default;
};

}  // namespace geometry_msgs

namespace sensor_msgs {

// Units as in ROS: rad/s, m/s^2; covariances row-major 3x3.
struct Imu {
  std_msgs::Header header;
  geometry_msgs::Quaternion orientation;
  std::array<double, 9> orientation_covariance{};
  geometry_msgs::Vector3 angular_velocity;
  std::array<double, 9> angular_velocity_covariance{};
  geometry_msgs::Vector3 linear_acceleration;
  std::array<double, 9> linear_acceleration_covariance{};
  friend bool operator==(const Imu&, const Imu&) = default;
};

struct PointField {
  // sensor_msgs/PointField datatype constants.
  static constexpr std::uint8_t kInt8 = 1;
  static constexpr std::uint8_t kUint8 = 2;
  static constexpr std::uint8_t kInt16 = 3;
  static constexpr std::uint8_t kUint16 = 4;
  static constexpr std::uint8_t kInt32 = 5;
  static constexpr std::uint8_t kUint32 = 6;
  static constexpr std::uint8_t kFloat32 = 7;
  static constexpr std::uint8_t kFloat64 = 8;

  std::string name;
  std::uint32_t offset = 0;  // byte offset inside one point
  std::uint8_t datatype = 0;
  std::uint32_t count = 1;  // elements of this field per point
  friend bool operator==(const PointField&, const PointField&) = default;
};

// Size in bytes of one element of a PointField datatype; 0 for an unknown datatype.
std::size_t point_field_size(std::uint8_t datatype);

struct PointCloud2 {
  std_msgs::Header header;
  std::uint32_t height = 1;
  std::uint32_t width = 0;
  std::vector<PointField> fields;
  bool is_bigendian = false;
  std::uint32_t point_step = 0;  // bytes per point
  std::uint32_t row_step = 0;    // bytes per row
  std::vector<std::uint8_t> data;
  bool is_dense = false;
  friend bool operator==(const PointCloud2&, const PointCloud2&) = default;
};

struct Image {
  std_msgs::Header header;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string encoding;  // "mono8", "bgr8", "rgb8", "bayer_rggb8", "mono16", ...
  std::uint8_t is_bigendian = 0;
  std::uint32_t step = 0;  // bytes per row
  std::vector<std::uint8_t> data;
  friend bool operator==(const Image&, const Image&) = default;
};

struct CompressedImage {
  std_msgs::Header header;
  std::string format;  // "jpeg", "png", "bgr8; jpeg compressed bgr8", ...
  std::vector<std::uint8_t> data;
  friend bool operator==(const CompressedImage&, const CompressedImage&) = default;
};

}  // namespace sensor_msgs

namespace livox_ros_driver {

struct CustomPoint {
  std::uint32_t offset_time = 0;  // ns after CustomMsg::timebase
  float x = 0;                    // m
  float y = 0;
  float z = 0;
  std::uint8_t reflectivity = 0;
  std::uint8_t tag = 0;
  std::uint8_t line = 0;
  friend bool operator==(const CustomPoint&, const CustomPoint&) = default;
};

struct CustomMsg {
  std_msgs::Header header;
  std::uint64_t timebase = 0;  // ns, time of the first point
  std::uint32_t point_num = 0;
  std::uint8_t lidar_id = 0;
  std::array<std::uint8_t, 3> rsvd{};
  std::vector<CustomPoint> points;
  friend bool operator==(const CustomMsg&, const CustomMsg&) = default;
};

}  // namespace livox_ros_driver

namespace ouster_ros {

// One raw UDP payload (lidar or IMU packet) as ouster-ros records it.
struct PacketMsg {
  std::vector<std::uint8_t> buf;
  friend bool operator==(const PacketMsg&, const PacketMsg&) = default;
};

}  // namespace ouster_ros

// ROS type name, md5sum and full message_definition (the text `gendeps --cat` produces: the
// message, then each dependency after a line of 80 '=' and "MSG: <type>").
template <class Msg>
struct MessageTraits;

template <>
struct MessageTraits<std_msgs::Header> {
  static constexpr std::string_view type = "std_msgs/Header";
  static constexpr std::string_view md5sum = "2176decaecbce78abc3b96ef049fabed";
  static std::string_view definition();
};
template <>
struct MessageTraits<std_msgs::String> {
  static constexpr std::string_view type = "std_msgs/String";
  static constexpr std::string_view md5sum = "992ce8a1687cec8c8bd883ec73ca41d1";
  static std::string_view definition();
};
template <>
struct MessageTraits<sensor_msgs::Imu> {
  static constexpr std::string_view type = "sensor_msgs/Imu";
  static constexpr std::string_view md5sum = "6a62c6daae103f4ff57a132d6f95cec2";
  static std::string_view definition();
};
template <>
struct MessageTraits<sensor_msgs::PointCloud2> {
  static constexpr std::string_view type = "sensor_msgs/PointCloud2";
  static constexpr std::string_view md5sum = "1158d486dd51d683ce2f1be655c3c181";
  static std::string_view definition();
};
template <>
struct MessageTraits<sensor_msgs::Image> {
  static constexpr std::string_view type = "sensor_msgs/Image";
  static constexpr std::string_view md5sum = "060021388200f6f0f447d0fcd9c64743";
  static std::string_view definition();
};
template <>
struct MessageTraits<sensor_msgs::CompressedImage> {
  static constexpr std::string_view type = "sensor_msgs/CompressedImage";
  static constexpr std::string_view md5sum = "8f7a12909da2c9d3332d540a0977563f";
  static std::string_view definition();
};
template <>
struct MessageTraits<livox_ros_driver::CustomMsg> {
  static constexpr std::string_view type = "livox_ros_driver/CustomMsg";
  static constexpr std::string_view md5sum = "e4d6829bdfe657cb6c21a746c86b21a6";
  static std::string_view definition();
};
template <>
struct MessageTraits<ouster_ros::PacketMsg> {
  static constexpr std::string_view type = "ouster_ros/PacketMsg";
  static constexpr std::string_view md5sum = "4f7b5949e76f86d01e96b0e33ba9b5e3";
  static std::string_view definition();
};

// Deserializers: `out` is overwritten; its vectors keep their capacity, so decoding a stream of
// messages into the same object does not allocate once the buffers are large enough.
void deserialize(std::span<const std::byte> bytes, std_msgs::Header& out);
void deserialize(std::span<const std::byte> bytes, std_msgs::String& out);
void deserialize(std::span<const std::byte> bytes, sensor_msgs::Imu& out);
void deserialize(std::span<const std::byte> bytes, sensor_msgs::PointCloud2& out);
void deserialize(std::span<const std::byte> bytes, sensor_msgs::Image& out);
void deserialize(std::span<const std::byte> bytes, sensor_msgs::CompressedImage& out);
void deserialize(std::span<const std::byte> bytes, livox_ros_driver::CustomMsg& out);
void deserialize(std::span<const std::byte> bytes, ouster_ros::PacketMsg& out);

template <class Msg>
Msg deserialize(std::span<const std::byte> bytes) {
  Msg msg;
  deserialize(bytes, msg);
  return msg;
}

// Serializers: `out` is cleared and filled with the ROS1 wire bytes. Fields are written as they
// are (a CustomMsg's point_num or a PointCloud2's row_step are not recomputed). Throws livod::Error
// if a string or array is longer than the u32 the wire allows.
void serialize(const std_msgs::Header& msg, std::vector<std::byte>& out);
void serialize(const std_msgs::String& msg, std::vector<std::byte>& out);
void serialize(const sensor_msgs::Imu& msg, std::vector<std::byte>& out);
void serialize(const sensor_msgs::PointCloud2& msg, std::vector<std::byte>& out);
void serialize(const sensor_msgs::Image& msg, std::vector<std::byte>& out);
void serialize(const sensor_msgs::CompressedImage& msg, std::vector<std::byte>& out);
void serialize(const livox_ros_driver::CustomMsg& msg, std::vector<std::byte>& out);
void serialize(const ouster_ros::PacketMsg& msg, std::vector<std::byte>& out);

template <class Msg>
std::vector<std::byte> serialize(const Msg& msg) {
  std::vector<std::byte> out;
  serialize(msg, out);
  return out;
}

}  // namespace livod::io::rosbag

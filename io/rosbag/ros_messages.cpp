#include "io/rosbag/ros_messages.hpp"

#include <cstring>

namespace livod::io::rosbag {
namespace {

// Full message_definition texts, written from the ROS message specs (comments left out: they do
// not take part in the md5sum and readers ignore them). Layout as genmsg's compute_full_text:
// the message, then for each dependency a separator line of 80 '=', "MSG: <type>", its text.
constexpr std::string_view kHeaderDefinition =
    "uint32 seq\n"
    "time stamp\n"
    "string frame_id\n";

constexpr std::string_view kStringDefinition = "string data\n";

constexpr std::string_view kImuDefinition =
    "Header header\n"
    "geometry_msgs/Quaternion orientation\n"
    "float64[9] orientation_covariance\n"
    "geometry_msgs/Vector3 angular_velocity\n"
    "float64[9] angular_velocity_covariance\n"
    "geometry_msgs/Vector3 linear_acceleration\n"
    "float64[9] linear_acceleration_covariance\n"
    "\n"
    "================================================================================\n"
    "MSG: std_msgs/Header\n"
    "uint32 seq\n"
    "time stamp\n"
    "string frame_id\n"
    "\n"
    "================================================================================\n"
    "MSG: geometry_msgs/Quaternion\n"
    "float64 x\n"
    "float64 y\n"
    "float64 z\n"
    "float64 w\n"
    "\n"
    "================================================================================\n"
    "MSG: geometry_msgs/Vector3\n"
    "float64 x\n"
    "float64 y\n"
    "float64 z\n";

constexpr std::string_view kPointCloud2Definition =
    "Header header\n"
    "uint32 height\n"
    "uint32 width\n"
    "PointField[] fields\n"
    "bool is_bigendian\n"
    "uint32 point_step\n"
    "uint32 row_step\n"
    "uint8[] data\n"
    "bool is_dense\n"
    "\n"
    "================================================================================\n"
    "MSG: std_msgs/Header\n"
    "uint32 seq\n"
    "time stamp\n"
    "string frame_id\n"
    "\n"
    "================================================================================\n"
    "MSG: sensor_msgs/PointField\n"
    "uint8 INT8 = 1\n"
    "uint8 UINT8 = 2\n"
    "uint8 INT16 = 3\n"
    "uint8 UINT16 = 4\n"
    "uint8 INT32 = 5\n"
    "uint8 UINT32 = 6\n"
    "uint8 FLOAT32 = 7\n"
    "uint8 FLOAT64 = 8\n"
    "string name\n"
    "uint32 offset\n"
    "uint8 datatype\n"
    "uint32 count\n";

constexpr std::string_view kImageDefinition =
    "Header header\n"
    "uint32 height\n"
    "uint32 width\n"
    "string encoding\n"
    "uint8 is_bigendian\n"
    "uint32 step\n"
    "uint8[] data\n"
    "\n"
    "================================================================================\n"
    "MSG: std_msgs/Header\n"
    "uint32 seq\n"
    "time stamp\n"
    "string frame_id\n";

constexpr std::string_view kCompressedImageDefinition =
    "Header header\n"
    "string format\n"
    "uint8[] data\n"
    "\n"
    "================================================================================\n"
    "MSG: std_msgs/Header\n"
    "uint32 seq\n"
    "time stamp\n"
    "string frame_id\n";

constexpr std::string_view kLivoxCustomMsgDefinition =
    "Header header\n"
    "uint64 timebase\n"
    "uint32 point_num\n"
    "uint8 lidar_id\n"
    "uint8[3] rsvd\n"
    "CustomPoint[] points\n"
    "\n"
    "================================================================================\n"
    "MSG: std_msgs/Header\n"
    "uint32 seq\n"
    "time stamp\n"
    "string frame_id\n"
    "\n"
    "================================================================================\n"
    "MSG: livox_ros_driver/CustomPoint\n"
    "uint32 offset_time\n"
    "float32 x\n"
    "float32 y\n"
    "float32 z\n"
    "uint8 reflectivity\n"
    "uint8 tag\n"
    "uint8 line\n";

constexpr std::string_view kOusterPacketMsgDefinition = "uint8[] buf\n";

// Wire sizes used to bound array counts before allocating.
constexpr std::size_t kPointFieldMinWireSize = 4 + 4 + 1 + 4;  // empty name, offset, type, count
constexpr std::size_t kCustomPointWireSize = 4 + 3 * 4 + 3;

void read_header(RosReader& r, std_msgs::Header& h) {
  h.seq = r.read<std::uint32_t>();
  h.stamp = r.read_time();
  h.frame_id = r.read_string();
}

void write_header(RosWriter& w, const std_msgs::Header& h) {
  w.write(h.seq);
  w.write_time(h.stamp);
  w.write_string(h.frame_id);
}

void read_uint8_array(RosReader& r, std::vector<std::uint8_t>& out) {
  const auto bytes = r.read_byte_array();
  out.resize(bytes.size());
  if (!bytes.empty()) std::memcpy(out.data(), bytes.data(), bytes.size());
}

void write_uint8_array(RosWriter& w, const std::vector<std::uint8_t>& bytes) {
  w.write_byte_array(std::as_bytes(std::span(bytes)));
}

void read_vector3(RosReader& r, geometry_msgs::Vector3& v) {
  v.x = r.read<double>();
  v.y = r.read<double>();
  v.z = r.read<double>();
}

void write_vector3(RosWriter& w, const geometry_msgs::Vector3& v) {
  w.write(v.x);
  w.write(v.y);
  w.write(v.z);
}

void read_covariance(RosReader& r, std::array<double, 9>& c) {
  for (double& v : c) v = r.read<double>();
}

void write_covariance(RosWriter& w, const std::array<double, 9>& c) {
  for (double v : c) w.write(v);
}

// Runs `body` over a reader for the whole message and insists that it consumes every byte.
template <class Msg, class Body>
void read_message(std::span<const std::byte> bytes, Body&& body) {
  RosReader r(bytes, MessageTraits<Msg>::type);
  body(r);
  r.expect_end();
}

template <class Body>
void write_message(std::vector<std::byte>& out, Body&& body) {
  out.clear();
  RosWriter w(out);
  body(w);
}

}  // namespace

std::string_view MessageTraits<std_msgs::Header>::definition() {
  return kHeaderDefinition;
}
std::string_view MessageTraits<std_msgs::String>::definition() {
  return kStringDefinition;
}
std::string_view MessageTraits<sensor_msgs::Imu>::definition() {
  return kImuDefinition;
}
std::string_view MessageTraits<sensor_msgs::PointCloud2>::definition() {
  return kPointCloud2Definition;
}
std::string_view MessageTraits<sensor_msgs::Image>::definition() {
  return kImageDefinition;
}
std::string_view MessageTraits<sensor_msgs::CompressedImage>::definition() {
  return kCompressedImageDefinition;
}
std::string_view MessageTraits<livox_ros_driver::CustomMsg>::definition() {
  return kLivoxCustomMsgDefinition;
}
std::string_view MessageTraits<ouster_ros::PacketMsg>::definition() {
  return kOusterPacketMsgDefinition;
}

std::size_t sensor_msgs::point_field_size(std::uint8_t datatype) {
  switch (datatype) {
    case PointField::kInt8:
    case PointField::kUint8:
      return 1;
    case PointField::kInt16:
    case PointField::kUint16:
      return 2;
    case PointField::kInt32:
    case PointField::kUint32:
    case PointField::kFloat32:
      return 4;
    case PointField::kFloat64:
      return 8;
    default:
      return 0;
  }
}

// ---- deserializers ---------------------------------------------------------------------------

void deserialize(std::span<const std::byte> bytes, std_msgs::Header& out) {
  read_message<std_msgs::Header>(bytes, [&](RosReader& r) { read_header(r, out); });
}

void deserialize(std::span<const std::byte> bytes, std_msgs::String& out) {
  read_message<std_msgs::String>(bytes, [&](RosReader& r) { out.data = r.read_string(); });
}

void deserialize(std::span<const std::byte> bytes, sensor_msgs::Imu& out) {
  read_message<sensor_msgs::Imu>(bytes, [&](RosReader& r) {
    read_header(r, out.header);
    out.orientation.x = r.read<double>();
    out.orientation.y = r.read<double>();
    out.orientation.z = r.read<double>();
    out.orientation.w = r.read<double>();
    read_covariance(r, out.orientation_covariance);
    read_vector3(r, out.angular_velocity);
    read_covariance(r, out.angular_velocity_covariance);
    read_vector3(r, out.linear_acceleration);
    read_covariance(r, out.linear_acceleration_covariance);
  });
}

void deserialize(std::span<const std::byte> bytes, sensor_msgs::PointCloud2& out) {
  read_message<sensor_msgs::PointCloud2>(bytes, [&](RosReader& r) {
    read_header(r, out.header);
    out.height = r.read<std::uint32_t>();
    out.width = r.read<std::uint32_t>();
    const std::uint32_t n_fields = r.read_count(kPointFieldMinWireSize, "fields");
    out.fields.resize(n_fields);
    for (auto& f : out.fields) {
      f.name = r.read_string();
      f.offset = r.read<std::uint32_t>();
      f.datatype = r.read<std::uint8_t>();
      f.count = r.read<std::uint32_t>();
    }
    out.is_bigendian = r.read_bool();
    out.point_step = r.read<std::uint32_t>();
    out.row_step = r.read<std::uint32_t>();
    read_uint8_array(r, out.data);
    out.is_dense = r.read_bool();
  });
}

void deserialize(std::span<const std::byte> bytes, sensor_msgs::Image& out) {
  read_message<sensor_msgs::Image>(bytes, [&](RosReader& r) {
    read_header(r, out.header);
    out.height = r.read<std::uint32_t>();
    out.width = r.read<std::uint32_t>();
    out.encoding = r.read_string();
    out.is_bigendian = r.read<std::uint8_t>();
    out.step = r.read<std::uint32_t>();
    read_uint8_array(r, out.data);
  });
}

void deserialize(std::span<const std::byte> bytes, sensor_msgs::CompressedImage& out) {
  read_message<sensor_msgs::CompressedImage>(bytes, [&](RosReader& r) {
    read_header(r, out.header);
    out.format = r.read_string();
    read_uint8_array(r, out.data);
  });
}

void deserialize(std::span<const std::byte> bytes, livox_ros_driver::CustomMsg& out) {
  read_message<livox_ros_driver::CustomMsg>(bytes, [&](RosReader& r) {
    read_header(r, out.header);
    out.timebase = r.read<std::uint64_t>();
    out.point_num = r.read<std::uint32_t>();
    out.lidar_id = r.read<std::uint8_t>();
    for (auto& b : out.rsvd) b = r.read<std::uint8_t>();
    const std::uint32_t n = r.read_count(kCustomPointWireSize, "points");
    out.points.resize(n);
    for (auto& p : out.points) {
      p.offset_time = r.read<std::uint32_t>();
      p.x = r.read<float>();
      p.y = r.read<float>();
      p.z = r.read<float>();
      p.reflectivity = r.read<std::uint8_t>();
      p.tag = r.read<std::uint8_t>();
      p.line = r.read<std::uint8_t>();
    }
  });
}

void deserialize(std::span<const std::byte> bytes, ouster_ros::PacketMsg& out) {
  read_message<ouster_ros::PacketMsg>(bytes, [&](RosReader& r) { read_uint8_array(r, out.buf); });
}

// ---- serializers -----------------------------------------------------------------------------

void serialize(const std_msgs::Header& msg, std::vector<std::byte>& out) {
  write_message(out, [&](RosWriter& w) { write_header(w, msg); });
}

void serialize(const std_msgs::String& msg, std::vector<std::byte>& out) {
  write_message(out, [&](RosWriter& w) { w.write_string(msg.data); });
}

void serialize(const sensor_msgs::Imu& msg, std::vector<std::byte>& out) {
  write_message(out, [&](RosWriter& w) {
    write_header(w, msg.header);
    w.write(msg.orientation.x);
    w.write(msg.orientation.y);
    w.write(msg.orientation.z);
    w.write(msg.orientation.w);
    write_covariance(w, msg.orientation_covariance);
    write_vector3(w, msg.angular_velocity);
    write_covariance(w, msg.angular_velocity_covariance);
    write_vector3(w, msg.linear_acceleration);
    write_covariance(w, msg.linear_acceleration_covariance);
  });
}

void serialize(const sensor_msgs::PointCloud2& msg, std::vector<std::byte>& out) {
  write_message(out, [&](RosWriter& w) {
    write_header(w, msg.header);
    w.write(msg.height);
    w.write(msg.width);
    w.write_count(msg.fields.size());
    for (const auto& f : msg.fields) {
      w.write_string(f.name);
      w.write(f.offset);
      w.write(f.datatype);
      w.write(f.count);
    }
    w.write_bool(msg.is_bigendian);
    w.write(msg.point_step);
    w.write(msg.row_step);
    write_uint8_array(w, msg.data);
    w.write_bool(msg.is_dense);
  });
}

void serialize(const sensor_msgs::Image& msg, std::vector<std::byte>& out) {
  write_message(out, [&](RosWriter& w) {
    write_header(w, msg.header);
    w.write(msg.height);
    w.write(msg.width);
    w.write_string(msg.encoding);
    w.write(msg.is_bigendian);
    w.write(msg.step);
    write_uint8_array(w, msg.data);
  });
}

void serialize(const sensor_msgs::CompressedImage& msg, std::vector<std::byte>& out) {
  write_message(out, [&](RosWriter& w) {
    write_header(w, msg.header);
    w.write_string(msg.format);
    write_uint8_array(w, msg.data);
  });
}

void serialize(const livox_ros_driver::CustomMsg& msg, std::vector<std::byte>& out) {
  write_message(out, [&](RosWriter& w) {
    write_header(w, msg.header);
    w.write(msg.timebase);
    w.write(msg.point_num);
    w.write(msg.lidar_id);
    for (auto b : msg.rsvd) w.write(b);
    w.write_count(msg.points.size());
    out.reserve(out.size() + msg.points.size() * kCustomPointWireSize);
    for (const auto& p : msg.points) {
      w.write(p.offset_time);
      w.write(p.x);
      w.write(p.y);
      w.write(p.z);
      w.write(p.reflectivity);
      w.write(p.tag);
      w.write(p.line);
    }
  });
}

void serialize(const ouster_ros::PacketMsg& msg, std::vector<std::byte>& out) {
  write_message(out, [&](RosWriter& w) { write_uint8_array(w, msg.buf); });
}

}  // namespace livod::io::rosbag

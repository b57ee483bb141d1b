// BagWriter: round trips through BagReader for every compression, rosbag-compatible layout,
// byte-for-byte determinism.

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

#include "io/rosbag/bag_reader.hpp"
#include "io/rosbag/bag_writer.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::io::rosbag {
namespace {

struct Recorded {
  std::string topic;
  std::int64_t time_ns;
  std::vector<std::byte> data;
  friend bool operator==(const Recorded&, const Recorded&) = default;
};

std::vector<Recorded> read_all(const BagReader& bag) {
  std::vector<Recorded> out;
  auto cursor = bag.read();
  while (auto m = cursor.next()) {
    out.push_back({m->connection->topic, m->time_ns, {m->data.begin(), m->data.end()}});
  }
  return out;
}

std::vector<std::byte> file_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::vector<char> chars((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::byte> out(chars.size());
  std::memcpy(out.data(), chars.data(), chars.size());
  return out;
}

std::uint32_t u32_at(const std::vector<std::byte>& b, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

constexpr std::int64_t kT0 = 1'700'000'000'000'000'000;

// A sequence of every supported message type, some written out of time order, with a chunk
// threshold small enough to give many chunks.
std::vector<Recorded> write_mixed_bag(const std::filesystem::path& path, Compression compression) {
  BagWriter::Options options;
  options.compression = compression;
  options.chunk_threshold = 16 * 1024;
  BagWriter bag(path, options);
  const auto imu_conn = bag.add_connection<sensor_msgs::Imu>("/imu");
  const auto cloud_conn = bag.add_connection<sensor_msgs::PointCloud2>("/points");
  const auto livox_conn = bag.add_connection<livox_ros_driver::CustomMsg>("/livox/lidar");
  const auto image_conn = bag.add_connection<sensor_msgs::Image>("/cam/image_raw");
  const auto jpeg_conn = bag.add_connection<sensor_msgs::CompressedImage>("/cam/compressed");
  const auto packet_conn = bag.add_connection<ouster_ros::PacketMsg>("/os/lidar_packets");
  const auto text_conn = bag.add_connection<std_msgs::String>("/metadata");

  std::vector<Recorded> written;
  auto keep = [&](const std::string& topic, std::int64_t t, const auto& msg) {
    written.push_back({topic, t, serialize(msg)});
  };
  std_msgs::String text;
  text.data = "{\"sensor\": \"sim\"}";
  bag.write(text_conn, kT0, text);
  keep("/metadata", kT0, text);
  for (int i = 0; i < 400; ++i) {
    const std::int64_t t = kT0 + i * 5'000'000;  // 200 Hz
    sensor_msgs::Imu imu;
    imu.header.seq = static_cast<std::uint32_t>(i);
    imu.header.stamp = RosTime::from_ns(t);
    imu.linear_acceleration = {0.01 * i, -0.02 * i, 9.81};
    imu.orientation.w = 1;
    bag.write(imu_conn, t, imu);
    keep("/imu", t, imu);
    if (i % 20 == 10) {
      // The scan arrives 30 ms after its start stamp, so it is written after later IMU samples
      // but carries an earlier record time.
      const std::int64_t ts = t - 30'000'000;
      livox_ros_driver::CustomMsg scan;
      scan.header.stamp = RosTime::from_ns(ts);
      scan.timebase = static_cast<std::uint64_t>(ts);
      for (std::uint32_t k = 0; k < 300; ++k) {
        scan.points.push_back(
            {k * 1000, 0.01f * k, 1.0f, -0.5f, 7, 0, static_cast<std::uint8_t>(k % 6)});
      }
      scan.point_num = 300;
      bag.write(livox_conn, ts, scan);
      keep("/livox/lidar", ts, scan);

      sensor_msgs::PointCloud2 cloud;
      cloud.header = scan.header;
      cloud.width = 100;
      cloud.fields = {{"x", 0, sensor_msgs::PointField::kFloat32, 1}};
      cloud.point_step = 4;
      cloud.row_step = 400;
      cloud.data.assign(400, static_cast<std::uint8_t>(i));
      bag.write(cloud_conn, ts, cloud);
      keep("/points", ts, cloud);

      ouster_ros::PacketMsg packet;
      packet.buf.assign(8448, static_cast<std::uint8_t>(i * 3));
      bag.write(packet_conn, t, packet);
      keep("/os/lidar_packets", t, packet);
    }
    if (i % 50 == 0) {
      sensor_msgs::Image image;
      image.header.stamp = RosTime::from_ns(t);
      image.width = 64;
      image.height = 48;
      image.step = 64;
      image.encoding = "mono8";
      for (int p = 0; p < 64 * 48; ++p) image.data.push_back(static_cast<std::uint8_t>(p * 7 + i));
      bag.write(image_conn, t, image);
      keep("/cam/image_raw", t, image);

      sensor_msgs::CompressedImage jpeg;
      jpeg.header = image.header;
      jpeg.format = "jpeg";
      jpeg.data = {0xFF, 0xD8, static_cast<std::uint8_t>(i), 0xFF, 0xD9};
      bag.write(jpeg_conn, t, jpeg);
      keep("/cam/compressed", t, jpeg);
    }
  }
  bag.close();
  // Readers return time order; ties keep write order (file order).
  std::stable_sort(written.begin(), written.end(),
                   [](const Recorded& a, const Recorded& b) { return a.time_ns < b.time_ns; });
  return written;
}

class RosbagWriterCompression : public ::testing::TestWithParam<Compression> {};

TEST_P(RosbagWriterCompression, MixedTypesRoundTripInTimeOrder) {
  const auto dir = test::temp_dir("rosbag_writer_mixed");
  const auto path = dir / "mixed.bag";
  const auto written = write_mixed_bag(path, GetParam());
  const BagReader bag(path);
  EXPECT_GT(bag.chunk_count(), 10u);
  EXPECT_EQ(bag.chunk_compressions(),
            (std::map<std::string, std::size_t>{
                {std::string(compression_name(GetParam())), bag.chunk_count()}}));
  EXPECT_EQ(bag.message_count(), written.size());
  EXPECT_EQ(read_all(bag), written);

  // Connections carry the real type identity.
  for (const Connection& c : bag.connections()) {
    if (c.topic == "/livox/lidar") {
      EXPECT_EQ(c.type, "livox_ros_driver/CustomMsg");
      EXPECT_EQ(c.md5sum, "e4d6829bdfe657cb6c21a746c86b21a6");
      EXPECT_EQ(c.message_definition, MessageTraits<livox_ros_driver::CustomMsg>::definition());
    }
  }
  // Typed decoding of what came back.
  BagQuery q;
  q.topics = {"/livox/lidar"};
  auto cursor = bag.read(q);
  std::size_t scans = 0;
  while (auto m = cursor.next()) {
    const auto scan = m->as<livox_ros_driver::CustomMsg>();
    EXPECT_EQ(scan.points.size(), 300u);
    EXPECT_EQ(static_cast<std::int64_t>(scan.timebase), m->time_ns);
    ++scans;
  }
  EXPECT_EQ(scans, 20u);
}

TEST_P(RosbagWriterCompression, WritingTheSameSequenceTwiceGivesIdenticalBytes) {
  const auto dir = test::temp_dir("rosbag_writer_determinism");
  write_mixed_bag(dir / "a.bag", GetParam());
  write_mixed_bag(dir / "b.bag", GetParam());
  const auto a = file_bytes(dir / "a.bag");
  const auto b = file_bytes(dir / "b.bag");
  ASSERT_GT(a.size(), 4117u);
  EXPECT_TRUE(a == b) << "bags differ";
}

TEST_P(RosbagWriterCompression, RealBagRewrittenReadsBackIdentically) {
  // Every message of test1.bag (bz2, 10 chunks) through the writer and back.
  const BagReader original(test::data_path("rosbag1/test1.bag"));
  const auto dir = test::temp_dir("rosbag_writer_rewrite");
  const auto path = dir / "rewritten.bag";
  {
    BagWriter::Options options;
    options.compression = GetParam();
    BagWriter out(path, options);
    std::map<std::uint32_t, std::uint32_t> conn_map;
    for (const Connection& c : original.connections()) {
      conn_map[c.id] = out.add_connection(
          {c.topic, c.type, c.md5sum, c.message_definition, c.callerid, c.latching});
    }
    auto cursor = original.read();
    while (auto m = cursor.next()) out.write(conn_map.at(m->connection->id), m->time_ns, m->data);
    out.close();
  }
  const BagReader copy(path);
  EXPECT_EQ(copy.message_count("/imu/data"), 11865u);
  EXPECT_EQ(copy.message_count("/husky_velocity_controller/odom"), 3952u);
  EXPECT_EQ(copy.message_count("/fix"), 989u);
  EXPECT_EQ(copy.start_time_ns(), original.start_time_ns());
  EXPECT_EQ(copy.end_time_ns(), original.end_time_ns());
  EXPECT_EQ(read_all(copy), read_all(original));
  ASSERT_EQ(copy.connections().size(), 3u);
  EXPECT_EQ(copy.connections()[0].message_definition, original.connections()[0].message_definition);
}

std::string compression_test_name(const ::testing::TestParamInfo<Compression>& param) {
  return std::string(compression_name(param.param));
}

INSTANTIATE_TEST_SUITE_P(AllCompressions, RosbagWriterCompression,
                         ::testing::Values(Compression::kNone, Compression::kBz2,
                                           Compression::kLz4),
                         compression_test_name);

TEST(RosbagWriter, LayoutFollowsRosbag) {
  const auto dir = test::temp_dir("rosbag_writer_layout");
  const auto path = dir / "layout.bag";
  {
    BagWriter::Options options;
    options.compression = Compression::kLz4;
    BagWriter bag(path, options);
    const auto c = bag.add_connection<std_msgs::String>("/chatter");
    std_msgs::String s;
    s.data = "hello";
    bag.write(c, kT0, s);
    bag.close();
  }
  const auto b = file_bytes(path);
  ASSERT_GT(b.size(), 4200u);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(b.data()), 13), "#ROSBAG V2.0\n");
  // Bag header record: header + data = 4096 bytes, data is space padding, fields sorted.
  const std::uint32_t header_len = u32_at(b, 13);
  EXPECT_EQ(header_len + u32_at(b, 17 + header_len), 4096u);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(b.data()) + 21, 12), "chunk_count=");
  EXPECT_EQ(static_cast<char>(b[4116]), ' ');
  // The first chunk starts at 13 + 4104, as with rosbag: header fields compression, op, size.
  const std::uint32_t chunk_header_len = u32_at(b, 4117);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(b.data()) + 4125, 16), "compression=lz4\x04");
  // Chunk data is an LZ4 frame that roslz4 accepts: magic, FLG 0x64 (version 1, independent
  // blocks, content checksum, no block checksum, no content size), BD with a block size id of
  // 4..7 (liblz4 picks the smallest that holds this small chunk) and no reserved bits.
  const std::size_t data_at = 4117 + 4 + chunk_header_len + 4;
  EXPECT_EQ(u32_at(b, data_at), 0x184D2204u);
  EXPECT_EQ(static_cast<int>(b[data_at + 4]), 0x64);
  const int bd = static_cast<int>(b[data_at + 5]);
  EXPECT_EQ(bd & 0x8F, 0);
  EXPECT_GE(bd >> 4, 4);

  const BagReader bag(path);
  ASSERT_EQ(bag.connections().size(), 1u);
  EXPECT_EQ(bag.connections()[0].md5sum, "992ce8a1687cec8c8bd883ec73ca41d1");
  EXPECT_EQ(bag.connections()[0].message_definition, "string data\n");
  auto cursor = bag.read();
  const auto m = cursor.next();
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(m->as<std_msgs::String>().data, "hello");
  EXPECT_EQ(m->time_ns, kT0);
}

TEST(RosbagWriter, EmptyBagIsValid) {
  const auto dir = test::temp_dir("rosbag_writer_empty");
  { BagWriter bag(dir / "empty.bag"); }  // closed by the destructor
  const BagReader bag(dir / "empty.bag");
  EXPECT_EQ(bag.message_count(), 0u);
  EXPECT_EQ(bag.chunk_count(), 0u);
  EXPECT_FALSE(bag.start_time_ns().has_value());
  EXPECT_FALSE(bag.read().next().has_value());
}

TEST(RosbagWriter, RejectsInvalidUse) {
  const auto dir = test::temp_dir("rosbag_writer_errors");
  BagWriter bag(dir / "errors.bag");
  const auto c = bag.add_connection<sensor_msgs::Imu>("/imu");
  sensor_msgs::Imu imu;
  EXPECT_THROW(bag.write(c, 0, imu), Error);  // below ros::TIME_MIN
  EXPECT_THROW(bag.write(c, -5, imu), Error);
  EXPECT_THROW(bag.write(c, std::int64_t{1} << 62, imu), Error);  // beyond u32 seconds
  std_msgs::String s;
  EXPECT_THROW(bag.write(c, kT0, s), Error);        // wrong type for the connection
  EXPECT_THROW(bag.write(c + 1, kT0, imu), Error);  // unknown connection
  EXPECT_THROW(bag.add_connection(ConnectionSpec{}), Error);
  bag.write(c, kT0, imu);
  bag.close();
  EXPECT_THROW(bag.write(c, kT0, imu), Error);
  EXPECT_THROW(BagWriter(dir / "no_such_dir" / "x.bag"), Error);
}

}  // namespace
}  // namespace livod::io::rosbag

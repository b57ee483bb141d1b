// BagReader on the real ROS1 bags in shared/data/rosbag1 (see shared/data/README.md for the
// expected counts).

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "io/rosbag/bag_reader.hpp"
#include "io/rosbag/ros_md5.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::io::rosbag {
namespace {

constexpr std::string_view kImuMd5 = "6a62c6daae103f4ff57a132d6f95cec2";

std::filesystem::path bag_path(const std::string& name) {
  return test::data_path("rosbag1/" + name);
}

// Messages per topic from a full pass, checking time order on the way.
std::map<std::string, std::uint64_t> count_by_reading(const BagReader& bag, const BagQuery& q) {
  std::map<std::string, std::uint64_t> counts;
  auto cursor = bag.read(q);
  std::int64_t last = std::numeric_limits<std::int64_t>::min();
  while (auto m = cursor.next()) {
    EXPECT_GE(m->time_ns, last) << "messages must come in time order";
    last = m->time_ns;
    ++counts[m->connection->topic];
  }
  return counts;
}

TEST(RosbagReader, Test1BagCountsFromIndexAndFromMessages) {
  const BagReader bag(bag_path("test1.bag"));
  EXPECT_EQ(bag.message_count("/imu/data"), 11865u);
  EXPECT_EQ(bag.message_count("/husky_velocity_controller/odom"), 3952u);
  EXPECT_EQ(bag.message_count("/fix"), 989u);
  EXPECT_EQ(bag.message_count(), 11865u + 3952u + 989u);
  EXPECT_EQ(bag.chunk_count(), 10u);
  EXPECT_FALSE(bag.recovered());

  const auto counts = count_by_reading(bag, {});
  EXPECT_EQ(counts.at("/imu/data"), 11865u);
  EXPECT_EQ(counts.at("/husky_velocity_controller/odom"), 3952u);
  EXPECT_EQ(counts.at("/fix"), 989u);
  EXPECT_EQ(counts.size(), 3u);

  const auto topics = bag.topics();
  ASSERT_EQ(topics.size(), 3u);
  EXPECT_EQ(topics[0].topic, "/fix");
  EXPECT_EQ(topics[0].type, "sensor_msgs/NavSatFix");
  EXPECT_EQ(topics[1].type, "nav_msgs/Odometry");
  EXPECT_EQ(topics[2].type, "sensor_msgs/Imu");
  EXPECT_EQ(topics[2].md5sum, kImuMd5);
  EXPECT_EQ(bag.chunk_compressions(), (std::map<std::string, std::size_t>{{"bz2", 10}}));
}

TEST(RosbagReader, Test2BagCounts) {
  const BagReader bag(bag_path("test2.bag"));
  EXPECT_EQ(bag.message_count("/imu/data"), 3061u);
  EXPECT_EQ(bag.message_count("/jackal_velocity_controller/odom"), 3060u);
  const auto counts = count_by_reading(bag, {});
  EXPECT_EQ(counts.at("/imu/data"), 3061u);
  EXPECT_EQ(counts.at("/jackal_velocity_controller/odom"), 3060u);
  // Recorded in simulation time: 47.58 s to 108.781 s.
  EXPECT_EQ(bag.start_time_ns(), 47'580'000'000);
  EXPECT_EQ(bag.end_time_ns(), 108'781'000'000);
}

TEST(RosbagReader, TopicFilterReturnsOnlyThoseTopics) {
  const BagReader bag(bag_path("test1.bag"));
  BagQuery q;
  q.topics = {"/fix", "/no/such/topic"};
  const auto counts = count_by_reading(bag, q);
  EXPECT_EQ(counts, (std::map<std::string, std::uint64_t>{{"/fix", 989}}));
}

TEST(RosbagReader, TimeRangeQueryMatchesFullScan) {
  const BagReader bag(bag_path("test1.bag"));
  // Reference: every (topic, time) of the bag from an unfiltered pass.
  std::vector<std::pair<std::int64_t, std::string>> all;
  auto cursor = bag.read();
  while (auto m = cursor.next()) all.emplace_back(m->time_ns, m->connection->topic);
  ASSERT_EQ(all.size(), 16806u);
  EXPECT_EQ(all.front().first, *bag.start_time_ns());
  EXPECT_EQ(all.back().first, *bag.end_time_ns());

  // A window spanning a chunk boundary in the middle of the bag, bounds taken from real
  // message times to test that both ends are inclusive.
  const std::int64_t start = all[5000].first;
  const std::int64_t end = all[9000].first;
  BagQuery q;
  q.start_ns = start;
  q.end_ns = end;
  q.topics = {"/imu/data", "/fix"};
  std::vector<std::pair<std::int64_t, std::string>> expected;
  for (const auto& e : all) {
    if (e.first >= start && e.first <= end && e.second != "/husky_velocity_controller/odom") {
      expected.push_back(e);
    }
  }
  std::vector<std::pair<std::int64_t, std::string>> got;
  auto window = bag.read(q);
  while (auto m = window.next()) got.emplace_back(m->time_ns, m->connection->topic);
  EXPECT_GT(got.size(), 2000u);
  EXPECT_EQ(got, expected);

  // A single instant returns exactly the messages stamped with it.
  q.topics.clear();
  q.start_ns = q.end_ns = all[777].first;
  auto instant = bag.read(q);
  std::size_t n = 0;
  while (auto m = instant.next()) {
    EXPECT_EQ(m->time_ns, all[777].first);
    ++n;
  }
  EXPECT_EQ(n, static_cast<std::size_t>(std::count_if(all.begin(), all.end(), [&](const auto& e) {
              return e.first == all[777].first;
            })));

  // A window before the bag is empty.
  q.start_ns = 0;
  q.end_ns = *bag.start_time_ns() - 1;
  EXPECT_FALSE(bag.read(q).next().has_value());
}

TEST(RosbagReader, ImuValuesAreSane) {
  for (const char* name : {"test1.bag", "test2.bag"}) {
    SCOPED_TRACE(name);
    const BagReader bag(bag_path(name));
    BagQuery q;
    q.topics = {"/imu/data"};
    auto cursor = bag.read(q);
    double sum_norm = 0;
    std::size_t n = 0;
    sensor_msgs::Imu imu;
    while (auto m = cursor.next()) {
      m->decode_into(imu);
      const auto& a = imu.linear_acceleration;
      sum_norm += std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z);
      const auto& o = imu.orientation;
      EXPECT_NEAR(std::sqrt(o.x * o.x + o.y * o.y + o.z * o.z + o.w * o.w), 1.0, 1e-6);
      // The sensor stamp is close to the record time (< 0.2 s of transport latency).
      EXPECT_NEAR(static_cast<double>(imu.header.stamp.to_ns() - m->time_ns) * 1e-9, 0.0, 0.2);
      ++n;
    }
    ASSERT_GT(n, 3000u);
    EXPECT_NEAR(sum_norm / static_cast<double>(n), 9.81, 0.15);
  }
}

TEST(RosbagReader, ConnectionMd5sumsAreTheRosOnesAndMatchTheirDefinitions) {
  for (const char* name : {"test1.bag", "test2.bag", "ouster_packets_512x10.bag"}) {
    SCOPED_TRACE(name);
    const BagReader bag(bag_path(name));
    for (const Connection& c : bag.connections()) {
      EXPECT_EQ(compute_ros_md5sum(c.type, c.message_definition), c.md5sum) << c.type;
      if (c.type == "sensor_msgs/Imu") {
        EXPECT_EQ(c.md5sum, kImuMd5);
      }
    }
  }
}

TEST(RosbagReader, OusterPacketsAndMetadata) {
  const BagReader bag(bag_path("ouster_packets_512x10.bag"));
  EXPECT_EQ(bag.message_count("/os_node0/lidar_packets"), 32u);
  EXPECT_EQ(bag.message_count("/os_node0/imu_packets"), 10u);
  EXPECT_EQ(bag.message_count("/os_node0/metadata"), 1u);
  EXPECT_EQ(bag.chunk_compressions(), (std::map<std::string, std::size_t>{{"none", 1}}));

  std::map<std::string, std::set<std::size_t>> packet_sizes;
  std::optional<nlohmann::json> metadata;
  auto cursor = bag.read();
  while (auto m = cursor.next()) {
    if (m->connection->type == "std_msgs/String") {
      metadata = nlohmann::json::parse(m->as<std_msgs::String>().data);
    } else {
      packet_sizes[m->connection->topic].insert(m->as<ouster_ros::PacketMsg>().buf.size());
    }
  }
  ASSERT_TRUE(metadata.has_value());
  EXPECT_EQ((*metadata)["sensor_info"]["prod_line"], "OS-0-128");
  EXPECT_EQ((*metadata)["sensor_info"]["prod_sn"], "992108000265");
  const auto& format = (*metadata)["lidar_data_format"];
  EXPECT_EQ(format["udp_profile_lidar"], "RNG15_RFL8_NIR8");
  // 32 packets of 16 columns are exactly one 512-column frame.
  EXPECT_EQ(32 * format["columns_per_packet"].get<int>(), format["columns_per_frame"].get<int>());
  // RNG15_RFL8_NIR8: 32 B packet header + 16 columns x (12 B + 128 px x 4 B) + 32 B footer.
  EXPECT_EQ(packet_sizes["/os_node0/lidar_packets"],
            (std::set<std::size_t>{32 + 16 * (12 + 128 * 4) + 32}));
  EXPECT_EQ(packet_sizes["/os_node0/imu_packets"], (std::set<std::size_t>{48}));
}

TEST(RosbagReader, AsRejectsTheWrongType) {
  const BagReader bag(bag_path("test2.bag"));
  auto cursor = bag.read();
  const auto m = cursor.next();
  ASSERT_TRUE(m.has_value());
  ASSERT_EQ(m->connection->type, "sensor_msgs/Imu");
  EXPECT_THROW((void)m->as<std_msgs::String>(), Error);
  EXPECT_NO_THROW((void)m->as<sensor_msgs::Imu>());
}

TEST(RosbagReader, CursorOutlivesReader) {
  std::optional<MessageCursor> cursor;
  {
    const BagReader bag(bag_path("test2.bag"));
    cursor.emplace(bag.read());
  }
  std::size_t n = 0;
  while (cursor->next()) ++n;
  EXPECT_EQ(n, 3061u + 3060u);
}

TEST(RosbagReader, DescribeBagListsTopicsTypesCountsAndSpan) {
  const std::string text = describe_bag(bag_path("test1.bag"));
  EXPECT_NE(text.find("messages:    16806"), std::string::npos) << text;
  EXPECT_NE(text.find("bz2 [10/10 chunks]"), std::string::npos) << text;
  EXPECT_NE(text.find("sensor_msgs/Imu       [6a62c6daae103f4ff57a132d6f95cec2]"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("11865 msgs : sensor_msgs/Imu"), std::string::npos) << text;
  EXPECT_NE(text.find("989 msgs : sensor_msgs/NavSatFix"), std::string::npos) << text;
  EXPECT_NE(text.find("duration:    395.307 s"), std::string::npos) << text;
  EXPECT_NE(text.find("start:       1432235498.025043042"), std::string::npos) << text;
}

TEST(RosbagReader, MissingFileAndNonBagAreCleanErrors) {
  EXPECT_THROW(BagReader(std::filesystem::path("/nonexistent/file.bag")), Error);
  // A YAML file is not a bag.
  try {
    BagReader bag(bag_path("test_ekf_localization_node_bag1.yaml"));
    FAIL() << "a YAML file opened as a bag";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.offset(), 0u);
    EXPECT_NE(std::string(e.what()).find("not a ROS bag"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace livod::io::rosbag

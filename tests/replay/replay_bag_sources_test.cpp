// ROS1 bag topics as replay sources: Livox CustomMsg under both driver package names, and
// malformed messages counted and skipped (one corrupt message loses one measurement) while a topic
// that cannot be read at all stops the replay with the reason.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/error.hpp"
#include "daemon/config/config.hpp"
#include "daemon/replay/source_kinds.hpp"
#include "io/rosbag/bag_writer.hpp"
#include "tests/support/data_dir.hpp"

namespace livod {
namespace {

namespace rb = io::rosbag;

rb::livox_ros_driver::CustomMsg scan_message(std::uint64_t timebase_ns) {
  rb::livox_ros_driver::CustomMsg m;
  m.header.stamp = rb::RosTime::from_ns(static_cast<std::int64_t>(timebase_ns));
  m.timebase = timebase_ns;
  for (std::uint32_t k = 0; k < 40; ++k) {
    rb::livox_ros_driver::CustomPoint p;
    p.offset_time = k * 2'500'000;
    p.x = 2.0F + 0.1F * static_cast<float>(k);
    p.y = 1.0F;
    p.z = 0.5F;
    p.line = static_cast<std::uint8_t>(k % 4);
    m.points.push_back(p);
  }
  m.point_num = 40;
  return m;
}

daemon::SensorConfig dataset_lidar() {
  daemon::SensorConfig s;
  s.name = "lidar";
  s.driver = daemon::Driver::dataset_lidar;
  return s;
}

struct Drained {
  std::vector<LidarScan> scans;
  std::string summary;
};

Drained drain(daemon::replay::ReplaySource& source) {
  Drained out;
  drivers::DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& s) { out.scans.push_back(s); };
  while (source.peek_time()) source.deliver(sinks);
  source.finish(sinks);
  out.summary = source.summary();
  return out;
}

// A bag with one topic of `type`; `corrupt[i]` writes message i truncated to 7 bytes.
std::filesystem::path write_bag(const std::string& name, const std::string& type,
                                const std::vector<bool>& corrupt) {
  const auto path = test::temp_dir("bag-sources-" + name) / name;
  rb::BagWriter bag(path);
  rb::ConnectionSpec spec;
  spec.topic = "/livox/lidar";
  spec.type = type;
  spec.md5sum = std::string(rb::MessageTraits<rb::livox_ros_driver::CustomMsg>::md5sum);
  spec.message_definition =
      std::string(rb::MessageTraits<rb::livox_ros_driver::CustomMsg>::definition());
  const auto conn = bag.add_connection(spec);
  for (std::size_t i = 0; i < corrupt.size(); ++i) {
    const auto t = static_cast<std::uint64_t>(1'700'000'000'000'000'000LL + i * 100'000'000LL);
    std::vector<std::byte> bytes = rb::serialize(scan_message(t));
    if (corrupt[i]) bytes.resize(7);
    bag.write(conn, static_cast<std::int64_t>(t + 100'000'000), bytes);
  }
  bag.close();
  return path;
}

TEST(ReplayBagSources, LivoxDriver2CustomMsgReadsLikeDriver1) {
  const auto one = write_bag("driver1.bag", "livox_ros_driver/CustomMsg", {false, false, false});
  const auto two = write_bag("driver2.bag", "livox_ros_driver2/CustomMsg", {false, false, false});
  auto a = daemon::replay::make_bag_source(one, "/livox/lidar", dataset_lidar(), nullptr);
  auto b = daemon::replay::make_bag_source(two, "/livox/lidar", dataset_lidar(), nullptr);
  const Drained da = drain(*a);
  const Drained db = drain(*b);
  ASSERT_EQ(da.scans.size(), 3U);
  ASSERT_EQ(db.scans.size(), 3U);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(da.scans[i].start.sensor.ns, db.scans[i].start.sensor.ns);
    EXPECT_EQ(da.scans[i].x, db.scans[i].x);
    EXPECT_EQ(da.scans[i].t_offset_ns, db.scans[i].t_offset_ns);
    EXPECT_EQ(db.scans[i].ring[5], 1);
  }
  EXPECT_NE(db.summary.find("livox_ros_driver2/CustomMsg"), std::string::npos) << db.summary;
}

TEST(ReplayBagSources, CorruptMessagesAreCountedAndSkipped) {
  const auto path = write_bag("some-corrupt.bag", "livox_ros_driver/CustomMsg",
                              {false, true, false, true, true, false});
  auto source = daemon::replay::make_bag_source(path, "/livox/lidar", dataset_lidar(), nullptr);
  const Drained d = drain(*source);
  EXPECT_EQ(d.scans.size(), 3U);
  EXPECT_NE(d.summary.find("3 malformed"), std::string::npos) << d.summary;
}

TEST(ReplayBagSources, AnUnreadableTopicStopsWithTheReason) {
  const auto path =
      write_bag("all-corrupt.bag", "livox_ros_driver/CustomMsg", std::vector<bool>(8, true));
  auto source = daemon::replay::make_bag_source(path, "/livox/lidar", dataset_lidar(), nullptr);
  try {
    drain(*source);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("sensor 'lidar', topic '/livox/lidar'"), std::string::npos) << what;
    EXPECT_NE(what.find("the first 5 messages cannot be read"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace livod

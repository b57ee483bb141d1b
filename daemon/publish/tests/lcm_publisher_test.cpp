// LcmPublisher with the real liblcm: memq:// publish -> subscribe -> decode with the generated
// types, and file:// event logs written by liblcm and read back with io/lcm_log.

#include "daemon/publish/lcm_publisher.hpp"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <map>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "daemon/publish/lcm_messages.hpp"
#include "io/lcm_log.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon::publish {
namespace {

constexpr std::int64_t kUnixOffset = 1'600'000'000'000'000'000;

// A pose at t_ns; an IMU-propagated one is based on the filter update at the previous multiple of
// 100 ms strictly before t_ns (scans every 100 ms).
PoseRecord pose_at(std::int64_t t_ns, PoseSource source, double x) {
  PoseRecord p;
  p.t = MappedTime(t_ns);
  p.filter_t =
      source == PoseSource::kFilter ? p.t : MappedTime(t_ns - 1 - (t_ns - 1) % 100'000'000);
  p.has_filter_update = true;
  p.source = source;
  p.status = PoseStatus::kOk;
  p.R_world_body = Eigen::AngleAxisd(0.1 * x, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  p.p_world_body = {x, 2.0 * x, -x};
  p.v_world = {1.0, 0.0, 0.0};
  p.omega_body = {0.0, 0.0, 0.1};
  p.covariance.diagonal().setConstant(1e-4);
  return p;
}

HealthRecord health_at(std::int64_t unix_ns) {
  HealthRecord h;
  h.unix_time_ns = unix_ns;
  h.host_time = HostTime(unix_ns - kUnixOffset);
  h.version = "0.1.0";
  SensorHealthRecord s;
  s.name = "os1";
  s.kind = "ouster";
  s.state = SensorState::kStreaming;
  s.streams.push_back({"lidar", SensorState::kStreaming, 1000, 1280.0, 40.0, 100, 0, 0, 0, 0});
  h.sensors.push_back(s);
  h.threads.push_back({"scheduler", ThreadState::kAlive, 1000, 10, 2'000'000'000});
  return h;
}

CloudRecord cloud_at(std::int64_t t_ns, std::size_t n) {
  CloudRecord c;
  c.t = MappedTime(t_ns);
  for (std::size_t i = 0; i < n; ++i) {
    const auto f = static_cast<float>(i);
    c.points.push_back({f, f + 1.0F, f + 2.0F, 7.0F});
  }
  return c;
}

LcmOutputConfig config_for(const std::string& url) {
  LcmOutputConfig c;
  c.url = url;
  c.publish_cloud = true;
  c.cloud_max_points = 500;
  return c;
}

// Collects every message of every channel, decoded with the generated types.
struct Collector {
  std::vector<::livod::pose_t> poses;
  std::vector<::livod::pose_t> imu_poses;
  std::vector<::bot_core::pose_t> body_poses;
  std::vector<::livod::health_t> health;
  std::vector<::livod::cloud_t> clouds;
  std::vector<std::string> order;

  void add(const ::livod::pose_t& m) {
    (m.source == ::livod::pose_t::SOURCE_FILTER ? poses : imu_poses).push_back(m);
  }
  void add(const ::bot_core::pose_t& m) { body_poses.push_back(m); }
  void add(const ::livod::health_t& m) { health.push_back(m); }
  void add(const ::livod::cloud_t& m) { clouds.push_back(m); }
};

// Subscribed with subscribeFunction: LCM 1.3.1's member-function subscriptions trip UBSan's vptr
// check inside lcm-cpp-impl.hpp (the asan preset runs these tests).
template <class Message>
void collect(const lcm::ReceiveBuffer*, const std::string& channel, const Message* m,
             Collector* c) {
  c->add(*m);
  c->order.push_back(channel);
}

template <class Message>
void subscribe(lcm::LCM& lcm, const std::string& channel, Collector& c) {
  lcm.subscribeFunction(channel, &collect<Message>, &c);
}

void subscribe_all(lcm::LCM& lcm, Collector& c, const std::string& suffix) {
  subscribe<::livod::pose_t>(lcm, "LIVOD_POSE" + suffix, c);
  subscribe<::livod::pose_t>(lcm, "LIVOD_POSE_IMU" + suffix, c);
  subscribe<::bot_core::pose_t>(lcm, "POSE_BODY" + suffix, c);
  subscribe<::livod::health_t>(lcm, "LIVOD_HEALTH" + suffix, c);
  subscribe<::livod::cloud_t>(lcm, "LIVOD_CLOUD" + suffix, c);
}

void dispatch_all(lcm::LCM& lcm) {
  while (lcm.handleTimeout(0) > 0) {
  }
}

TEST(LcmPublisher, MemqPublishSubscribeDecode) {
  LcmOutputConfig config = config_for("memq://");
  config.channel_suffix = "_TEST";
  LcmPublisher publisher(config, Frames{"world", "os1.imu"});
  publisher.set_time_base(TimeBase{kUnixOffset});
  Collector c;
  subscribe_all(publisher.lcm(), c, "_TEST");

  // One scan: a filter pose, its cloud, then ten IMU-rate poses; then health.
  ASSERT_TRUE(publisher.publish_pose(pose_at(1'000'000'000, PoseSource::kFilter, 1.0)));
  ASSERT_TRUE(publisher.publish_cloud(cloud_at(1'000'000'000, 2000)));
  for (int i = 1; i <= 10; ++i) {
    ASSERT_TRUE(publisher.publish_pose(
        pose_at(1'000'000'000 + i * 10'000'000, PoseSource::kImuPropagated, 1.0 + 0.01 * i)));
  }
  ASSERT_TRUE(publisher.publish_health(health_at(kUnixOffset + 1'100'000'000)));
  dispatch_all(publisher.lcm());

  ASSERT_EQ(c.poses.size(), 1u);
  ASSERT_EQ(c.imu_poses.size(), 10u);
  ASSERT_EQ(c.clouds.size(), 1u);
  ASSERT_EQ(c.health.size(), 1u);
  // POSE_BODY follows the IMU-rate poses (publish_imu_rate is on).
  ASSERT_EQ(c.body_poses.size(), 10u);

  const ::livod::pose_t& p = c.poses[0];
  EXPECT_EQ(p.time_ns, kUnixOffset + 1'000'000'000);
  EXPECT_EQ(p.utime, (kUnixOffset + 1'000'000'000) / 1000);
  EXPECT_EQ(p.mapped_time_ns, 1'000'000'000);
  EXPECT_EQ(p.sequence, 0);
  EXPECT_EQ(p.body_frame, "os1.imu");
  EXPECT_EQ(p.world_frame, "world");
  EXPECT_EQ(p.position[0], 1.0);
  EXPECT_EQ(p.position[1], 2.0);
  EXPECT_EQ(p.covariance[4][4], 1e-4);
  for (std::size_t i = 0; i < c.imu_poses.size(); ++i) {
    EXPECT_EQ(c.imu_poses[i].sequence, static_cast<std::int64_t>(i));
    EXPECT_EQ(c.imu_poses[i].source, ::livod::pose_t::SOURCE_IMU_PROPAGATED);
    EXPECT_EQ(c.imu_poses[i].filter_time_ns, kUnixOffset + 1'000'000'000);
    EXPECT_EQ(c.body_poses[i].utime, c.imu_poses[i].utime);
    EXPECT_EQ(c.body_poses[i].pos[0], c.imu_poses[i].position[0]);
  }
  EXPECT_EQ(c.clouds[0].num_points, 500);
  EXPECT_EQ(c.clouds[0].source_points, 2000);
  EXPECT_EQ(c.clouds[0].time_ns, p.time_ns);
  EXPECT_EQ(c.health[0].sensors.at(0).name, "os1");
  EXPECT_EQ(c.health[0].sensors.at(0).streams.at(0).packets_per_s, 1280.0);
  EXPECT_EQ(c.order.front(), "LIVOD_POSE_TEST");

  const auto counters = publisher.channel_counters();
  ASSERT_EQ(counters.size(), 5u);
  const std::vector<std::string> names = {"LIVOD_POSE_TEST", "LIVOD_POSE_IMU_TEST",
                                          "POSE_BODY_TEST", "LIVOD_HEALTH_TEST",
                                          "LIVOD_CLOUD_TEST"};
  const std::vector<std::uint64_t> published = {1, 10, 10, 1, 1};
  for (std::size_t i = 0; i < counters.size(); ++i) {
    EXPECT_EQ(counters[i].name, names[i]);
    EXPECT_EQ(counters[i].published, published[i]) << names[i];
    EXPECT_EQ(counters[i].failed, 0u);
    EXPECT_GT(counters[i].bytes, 0u);
  }
  // Bytes: the encoded sizes, e.g. the cloud's 500 points of 16 bytes.
  EXPECT_GT(counters[4].bytes, 500u * 16u);
  EXPECT_EQ(counters[2].bytes, 10u * static_cast<std::uint64_t>(c.body_poses[0].getEncodedSize()));
}

TEST(LcmPublisher, SwitchesSelectChannels) {
  LcmOutputConfig config = config_for("memq://");
  config.publish_imu_rate = false;
  config.publish_cloud = false;
  config.channels.pose = "MY_POSE";
  config.channels.bot_core_pose = "MY_BODY";
  LcmPublisher publisher(config, Frames{"world", "imu"});
  Collector c;
  subscribe<::livod::pose_t>(publisher.lcm(), "MY_POSE", c);
  subscribe<::bot_core::pose_t>(publisher.lcm(), "MY_BODY", c);
  subscribe<::livod::pose_t>(publisher.lcm(), "LIVOD_POSE_IMU", c);
  subscribe<::livod::cloud_t>(publisher.lcm(), "LIVOD_CLOUD", c);

  EXPECT_TRUE(publisher.publish_pose(pose_at(1'000, PoseSource::kFilter, 1.0)));
  EXPECT_TRUE(publisher.publish_pose(pose_at(2'000, PoseSource::kImuPropagated, 1.0)));  // ignored
  EXPECT_TRUE(publisher.publish_cloud(cloud_at(1'000, 10)));                             // ignored
  dispatch_all(publisher.lcm());
  EXPECT_EQ(c.poses.size(), 1u);
  EXPECT_EQ(c.imu_poses.size(), 0u);
  EXPECT_EQ(c.clouds.size(), 0u);
  // Without IMU-rate poses, POSE_BODY follows the filter poses.
  ASSERT_EQ(c.body_poses.size(), 1u);
  EXPECT_EQ(c.body_poses[0].utime, 1);  // time base 0: mapped time 1000 ns

  const auto counters = publisher.channel_counters();
  ASSERT_EQ(counters.size(), 3u);  // pose, bot_core, health
  EXPECT_EQ(counters[0].name, "MY_POSE");
  EXPECT_EQ(counters[1].name, "MY_BODY");
  EXPECT_EQ(counters[2].name, "LIVOD_HEALTH");

  config.publish_bot_core_pose = false;
  LcmPublisher without_body(config, Frames{"world", "imu"});
  Collector c2;
  subscribe<::bot_core::pose_t>(without_body.lcm(), "MY_BODY", c2);
  EXPECT_TRUE(without_body.publish_pose(pose_at(1'000, PoseSource::kFilter, 1.0)));
  dispatch_all(without_body.lcm());
  EXPECT_EQ(c2.body_poses.size(), 0u);
  EXPECT_EQ(without_body.channel_counters().size(), 2u);
}

TEST(LcmPublisher, BadUrlIsAnErrorNamingIt) {
  for (const std::string url :
       {"udpm://300.1.2.3:7667", "nonsense://", "file:///nonexistent/livod/x.lcmlog?mode=w"}) {
    try {
      LcmPublisher publisher(config_for(url), Frames{"world", "imu"});
      ADD_FAILURE() << "no error for " << url;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(url), std::string::npos) << e.what();
    }
  }
}

TEST(LcmPublisher, OverlongChannelIsAnError) {
  LcmOutputConfig config = config_for("memq://");
  config.channel_suffix = std::string(60, 'X');
  EXPECT_THROW(LcmPublisher(config, Frames{"world", "imu"}), Error);
  config.channel_suffix.clear();
  config.channels.health.clear();
  EXPECT_THROW(LcmPublisher(config, Frames{"world", "imu"}), Error);
}

// liblcm's file:// provider writes an LCM event log; io/lcm_log reads it back event by event.
TEST(LcmPublisher, FileUrlWritesALogThatLcmLogReaderReads) {
  const auto dir = test::temp_dir("publish_file");
  const auto path = dir / "out.lcmlog";
  LcmOutputConfig config = config_for("file://" + path.string() + "?mode=w");
  config.channel_suffix = "_REPLAY";
  std::vector<std::string> expected_channels;
  {
    LcmPublisher publisher(config, Frames{"world", "hdl32.imu"});
    publisher.set_time_base(TimeBase{kUnixOffset});
    for (int scan = 0; scan < 5; ++scan) {
      const std::int64_t t = 1'000'000'000 + scan * 100'000'000;
      ASSERT_TRUE(publisher.publish_pose(pose_at(t, PoseSource::kFilter, scan)));
      ASSERT_TRUE(publisher.publish_cloud(cloud_at(t, 800)));
      expected_channels.insert(expected_channels.end(),
                               {"LIVOD_POSE_REPLAY", "LIVOD_CLOUD_REPLAY"});
      for (int i = 1; i <= 3; ++i) {
        ASSERT_TRUE(publisher.publish_pose(
            pose_at(t + i * 5'000'000, PoseSource::kImuPropagated, scan + 0.1 * i)));
        expected_channels.insert(expected_channels.end(),
                                 {"LIVOD_POSE_IMU_REPLAY", "POSE_BODY_REPLAY"});
      }
    }
    ASSERT_TRUE(publisher.publish_health(health_at(kUnixOffset + 2'000'000'000)));
    expected_channels.push_back("LIVOD_HEALTH_REPLAY");
  }  // closes the log

  io::LcmLogReader reader(path);
  std::vector<std::string> channels;
  std::map<std::string, int> count;
  std::int64_t expected_event = 0;
  while (const auto e = reader.next()) {
    EXPECT_EQ(e->event_number, expected_event++);
    const std::string channel(e->channel);
    channels.push_back(channel);
    const auto* data = e->data.data();
    const int size = static_cast<int>(e->data.size());
    if (channel == "LIVOD_POSE_REPLAY" || channel == "LIVOD_POSE_IMU_REPLAY") {
      ::livod::pose_t m;
      ASSERT_EQ(m.decode(data, 0, size), size);
      const bool imu = channel == "LIVOD_POSE_IMU_REPLAY";
      EXPECT_EQ(m.source,
                imu ? ::livod::pose_t::SOURCE_IMU_PROPAGATED : ::livod::pose_t::SOURCE_FILTER);
      EXPECT_EQ(m.sequence, count[channel]);
      EXPECT_EQ(m.body_frame, "hdl32.imu");
      if (!imu) {
        EXPECT_EQ(m.mapped_time_ns, 1'000'000'000 + count[channel] * 100'000'000);
        EXPECT_EQ(m.position[0], count[channel]);
      }
    } else if (channel == "POSE_BODY_REPLAY") {
      ::bot_core::pose_t m;
      ASSERT_EQ(m.decode(data, 0, size), size);
      EXPECT_GT(m.utime, kUnixOffset / 1000);
    } else if (channel == "LIVOD_CLOUD_REPLAY") {
      ::livod::cloud_t m;
      ASSERT_EQ(m.decode(data, 0, size), size);
      EXPECT_EQ(m.num_points, 500);
      EXPECT_EQ(m.source_points, 800);
      EXPECT_EQ(m.data.size(), 500u * 16u);
    } else if (channel == "LIVOD_HEALTH_REPLAY") {
      ::livod::health_t m;
      ASSERT_EQ(m.decode(data, 0, size), size);
      EXPECT_EQ(m.time_ns, kUnixOffset + 2'000'000'000);
      EXPECT_EQ(m.sensors.at(0).name, "os1");
    } else {
      ADD_FAILURE() << "unexpected channel " << channel;
    }
    ++count[channel];
  }
  EXPECT_EQ(channels, expected_channels);
  EXPECT_EQ(reader.stats().resyncs, 0u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace livod::daemon::publish

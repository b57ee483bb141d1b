// LcmPublisher over real UDP multicast (udpm://), recorded by a real `lcm-logger` process, inside
// the private network namespace that scripts/netns-run.sh provides (loopback only, multicast
// routed to lo): nothing leaves the machine. The log is read with io/lcm_log and every message is
// compared byte for byte with what the publisher encoded, then decoded with the generated types.

#include <gtest/gtest.h>

#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "core/error.hpp"
#include "daemon/publish/lcm_messages.hpp"
#include "daemon/publish/lcm_publisher.hpp"
#include "io/lcm_log.hpp"
#include "tests/support/data_dir.hpp"
#include "tests/support/lcm_logger.hpp"
#include "tests/support/process.hpp"

namespace livod::daemon::publish {
namespace {

// LCM's default group and port; ttl=0 as livod's default.
const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0";
constexpr std::int64_t kUnixOffset = 1'700'000'000'000'000'000;

bool inside_private_namespace() {
  const char* flag = std::getenv("LIVOD_NETNS");
  return flag != nullptr && std::string(flag) == "1";
}

// The namespace's UDP receive drops (kernel socket buffers full), for failure messages.
std::string udp_drops() {
  std::ifstream in("/proc/net/snmp");
  std::string header;
  std::string values;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("Udp:", 0) == 0) {
      if (header.empty()) {
        header = line;
      } else {
        values = line;
      }
    }
  }
  return "/proc/net/snmp " + header + " / " + values;
}

LcmOutputConfig udpm_config() {
  LcmOutputConfig c;
  c.url = kUrl;
  c.publish_cloud = true;
  c.cloud_max_points = 5000;  // 80 kB: fragmented over two datagrams
  return c;
}

PoseRecord pose(std::int64_t t, PoseSource source, std::int64_t filter_t, double x) {
  PoseRecord p;
  p.t = MappedTime(t);
  p.filter_t = MappedTime(filter_t);
  p.has_filter_update = true;
  p.source = source;
  p.status = PoseStatus::kOk;
  p.R_world_body = Eigen::AngleAxisd(x, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  p.p_world_body = {x, -x, 0.5 * x};
  p.covariance.diagonal().setConstant(1e-4);
  return p;
}

CloudRecord cloud(std::int64_t t, std::size_t n) {
  CloudRecord c;
  c.t = MappedTime(t);
  for (std::size_t i = 0; i < n; ++i) {
    const auto f = static_cast<float>(i) * 0.01F;
    c.points.push_back({f, 2.0F * f, -f, static_cast<float>(i % 256)});
  }
  return c;
}

HealthRecord health(std::int64_t unix_ns) {
  HealthRecord h;
  h.unix_time_ns = unix_ns;
  h.version = "test";
  SensorHealthRecord s;
  s.name = "os1";
  s.kind = "ouster";
  s.state = SensorState::kStreaming;
  h.sensors.push_back(s);
  return h;
}

template <class Message>
std::vector<std::uint8_t> encoded(const Message& m) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

using Expected = std::map<std::string, std::vector<std::vector<std::uint8_t>>>;

// Publishes a 2 s stretch at the rates of a 10 Hz LiDAR with a 100 Hz IMU, remembering what each
// channel should carry (the same converters, the same sequence numbers).
Expected publish_run(LcmPublisher& publisher) {
  const Frames frames{"world", "os1.imu"};
  const TimeBase base{kUnixOffset};
  Expected expected;
  std::int64_t imu_sequence = 0;
  const auto pace = [] { std::this_thread::sleep_for(std::chrono::milliseconds(1)); };
  for (int scan = 0; scan < 20; ++scan) {
    const std::int64_t t = 5'000'000'000 + scan * 100'000'000;
    const PoseRecord filter = pose(t, PoseSource::kFilter, t, 0.1 * scan);
    EXPECT_TRUE(publisher.publish_pose(filter));
    expected["LIVOD_POSE"].push_back(encoded(to_lcm_pose(filter, frames, base, scan)));
    pace();
    const CloudRecord c = cloud(t, 6000);
    EXPECT_TRUE(publisher.publish_cloud(c));
    expected["LIVOD_CLOUD"].push_back(encoded(to_lcm_cloud(c, "world", base, scan, 5000)));
    pace();
    for (int i = 1; i <= 10; ++i) {
      const PoseRecord p =
          pose(t + i * 10'000'000, PoseSource::kImuPropagated, t, 0.1 * scan + 0.01 * i);
      EXPECT_TRUE(publisher.publish_pose(p));
      expected["LIVOD_POSE_IMU"].push_back(encoded(to_lcm_pose(p, frames, base, imu_sequence++)));
      expected["POSE_BODY"].push_back(encoded(to_bot_core_pose(p, base)));
      pace();
    }
    if (scan % 5 == 4) {
      const HealthRecord h = health(kUnixOffset + t);
      const auto sequence = static_cast<std::int64_t>(expected["LIVOD_HEALTH"].size());
      EXPECT_TRUE(publisher.publish_health(h));
      expected["LIVOD_HEALTH"].push_back(encoded(to_lcm_health(h, sequence)));
      pace();
    }
  }
  return expected;
}

// One recording: "" when the log holds exactly what was published, else what differs.
std::string record_and_compare(const std::filesystem::path& dir) {
  const auto log = dir / "recorded.lcmlog";
  test::LcmLoggerProcess logger(kUrl, log);  // throws when it does not record
  LcmPublisher publisher(udpm_config(), Frames{"world", "os1.imu"});
  publisher.set_time_base(TimeBase{kUnixOffset});
  const Expected expected = publish_run(publisher);
  for (const ChannelCounters& c : publisher.channel_counters()) {
    const auto it = expected.find(c.name);
    const std::size_t n = it == expected.end() ? 0 : it->second.size();
    if (c.published != n || c.failed != 0) {
      return c.name + ": published " + std::to_string(c.published) + ", failed " +
             std::to_string(c.failed) + ", expected " + std::to_string(n);
    }
  }

  logger.stop();

  io::LcmLogReader reader(log);
  std::map<std::string, std::vector<std::vector<std::uint8_t>>> recorded;
  std::int64_t event = 0;
  while (const auto e = reader.next()) {
    if (e->event_number != event++) return "event numbers are not consecutive";
    if (e->channel == test::LcmLoggerProcess::kProbeChannel) continue;
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(e->data.data());
    recorded[std::string(e->channel)].emplace_back(bytes, bytes + e->data.size());
  }
  for (const auto& [channel, messages] : expected) {
    const auto& got = recorded[channel];
    if (got.size() != messages.size()) {
      std::string missing;
      for (std::size_t i = 0; i < messages.size(); ++i) {
        if (std::find(got.begin(), got.end(), messages[i]) == got.end()) {
          missing += " " + std::to_string(i);
        }
      }
      return channel + ": recorded " + std::to_string(got.size()) + " messages, published " +
             std::to_string(messages.size()) + " (missing:" + missing + "; " + udp_drops() + ")";
    }
    for (std::size_t i = 0; i < got.size(); ++i) {
      if (got[i] != messages[i]) return channel + ": message " + std::to_string(i) + " differs";
    }
  }
  if (recorded.size() != expected.size()) return "the log has channels nobody published";

  // Decoded with the generated types.
  for (std::size_t i = 0; i < recorded["LIVOD_POSE"].size(); ++i) {
    const auto& bytes = recorded["LIVOD_POSE"][i];
    ::livod::pose_t m;
    if (m.decode(bytes.data(), 0, static_cast<int>(bytes.size())) !=
            static_cast<int>(bytes.size()) ||
        m.sequence != static_cast<std::int64_t>(i) || m.body_frame != "os1.imu" ||
        m.time_ns != kUnixOffset + 5'000'000'000 + static_cast<std::int64_t>(i) * 100'000'000) {
      return "LIVOD_POSE message " + std::to_string(i) + " decodes wrongly";
    }
  }
  const auto& clouds = recorded["LIVOD_CLOUD"];
  ::livod::cloud_t c;
  if (c.decode(clouds.back().data(), 0, static_cast<int>(clouds.back().size())) < 0 ||
      c.num_points != 5000 || c.source_points != 6000 || c.data.size() != 5000u * 16u) {
    return "LIVOD_CLOUD decodes wrongly";
  }
  ::bot_core::pose_t body;
  const auto& b = recorded["POSE_BODY"].front();
  if (body.decode(b.data(), 0, static_cast<int>(b.size())) < 0 ||
      body.utime != (kUnixOffset + 5'010'000'000) / 1000) {
    return "POSE_BODY decodes wrongly";
  }
  ::livod::health_t h;
  const auto& hb = recorded["LIVOD_HEALTH"].back();
  if (h.decode(hb.data(), 0, static_cast<int>(hb.size())) < 0 || h.sensors.at(0).name != "os1") {
    return "LIVOD_HEALTH decodes wrongly";
  }
  return "";
}

TEST(LcmUdpm, LcmLoggerRecordsWhatThePublisherSends) {
  ASSERT_TRUE(inside_private_namespace())
      << "run this test through scripts/netns-run.sh (ctest does): it sends multicast";
  const auto dir = test::temp_dir("lcm_udpm");
  std::string failures;
  bool passed = false;
  // UDP may drop a datagram on a loaded machine even on loopback: one retry.
  for (int attempt = 1; attempt <= 2 && !passed; ++attempt) {
    const auto attempt_dir = dir / std::to_string(attempt);
    std::filesystem::create_directories(attempt_dir);
    std::string difference;
    try {
      difference = record_and_compare(attempt_dir);
    } catch (const std::exception& e) {
      difference = e.what();
    }
    passed = difference.empty();
    if (!passed) failures += "attempt " + std::to_string(attempt) + ": " + difference + "\n";
  }
  EXPECT_TRUE(passed) << failures;
  if (passed && !failures.empty()) std::cerr << "passed on retry after:\n" << failures;
  if (passed) std::filesystem::remove_all(dir);
}

// A publish that fails (here: the multicast route disappears, as when an interface goes down) is
// counted and reported, never thrown; publishing resumes when the route is back. Creating a udpm
// publisher without a route is an error naming the URL.
TEST(LcmUdpm, FailedPublishIsCountedAndRecovers) {
  ASSERT_TRUE(inside_private_namespace())
      << "run this test through scripts/netns-run.sh (ctest does): it changes routes";
  LcmPublisher publisher(udpm_config(), Frames{"world", "imu"});
  const auto counters = [&](const std::string& name) {
    for (const ChannelCounters& c : publisher.channel_counters()) {
      if (c.name == name) return c;
    }
    ADD_FAILURE() << "no channel " << name;
    return ChannelCounters{};
  };
  EXPECT_TRUE(publisher.publish_pose(pose(1'000, PoseSource::kImuPropagated, 0, 1.0)));

  ASSERT_EQ(test::run_process({"ip", "route", "del", "224.0.0.0/4", "dev", "lo"}), 0);
  bool ok = true;
  EXPECT_NO_THROW(ok = publisher.publish_pose(pose(2'000, PoseSource::kImuPropagated, 0, 1.0)));
  EXPECT_FALSE(ok);
  EXPECT_FALSE(publisher.publish_health(health(0)));
  EXPECT_EQ(counters("LIVOD_POSE_IMU").failed, 1u);
  EXPECT_EQ(counters("POSE_BODY").failed, 1u);
  EXPECT_EQ(counters("LIVOD_HEALTH").failed, 1u);
  EXPECT_EQ(counters("LIVOD_POSE_IMU").published, 1u);
  try {
    LcmPublisher without_route(udpm_config(), Frames{"world", "imu"});
    ADD_FAILURE() << "a udpm publisher without a multicast route was created";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(kUrl), std::string::npos) << e.what();
  }

  ASSERT_EQ(test::run_process({"ip", "route", "add", "224.0.0.0/4", "dev", "lo"}), 0);
  EXPECT_TRUE(publisher.publish_pose(pose(3'000, PoseSource::kImuPropagated, 0, 1.0)));
  EXPECT_EQ(counters("LIVOD_POSE_IMU").published, 2u);
  EXPECT_EQ(counters("LIVOD_POSE_IMU").failed, 1u);
}

}  // namespace
}  // namespace livod::daemon::publish

#include "drivers/livox/device.hpp"

#include <gtest/gtest.h>

#include "drivers/livox/sdk1_control.hpp"
#include "drivers/livox/sdk2_control.hpp"

namespace livod::livox {
namespace {

constexpr std::uint32_t kLidarIp = 0xC0A8010A;
constexpr std::uint32_t kHostIp = 0xC0A80132;

// A fake SDK1 LiDAR: broadcasts, ACKs every command with return code 0 unless told to be silent.
struct FakeSdk1 {
  bool silent = false;
  int handshakes = 0;
  int starts = 0;
  int heartbeats = 0;
  std::vector<std::byte> broadcast() const {
    sdk1::ControlFrame f{sdk1::PacketType::kMsg, 0, 0, sdk1::cmd::kBroadcast, {}};
    const std::string code = "3GGDJ6K00100101";
    for (char c : code) f.payload.push_back(static_cast<std::byte>(c));
    f.payload.push_back(std::byte{0});
    f.payload.push_back(std::byte{7});  // Avia
    f.payload.push_back(std::byte{0});
    f.payload.push_back(std::byte{0});
    return sdk1::encode(f);
  }
  std::vector<std::vector<std::byte>> answer(const std::vector<OutgoingFrame>& sent) {
    std::vector<std::vector<std::byte>> replies;
    for (const auto& o : sent) {
      EXPECT_EQ(o.dst_ip, kLidarIp);
      EXPECT_EQ(o.dst_port, 65000);
      sdk1::ControlFrame f;
      EXPECT_EQ(sdk1::parse(o.bytes, f), sdk1::ParseError::kNone);
      if (f.cmd_id == sdk1::cmd::kHandshake) {
        ++handshakes;
        EXPECT_EQ(f.payload.size(), 10u);
      }
      if (f.cmd_id == sdk1::cmd::kSampling) ++starts;
      if (f.cmd_id == sdk1::cmd::kHeartbeat) ++heartbeats;
      if (silent) continue;
      sdk1::ControlFrame ack{sdk1::PacketType::kAck, f.seq, f.cmd_set, f.cmd_id, {std::byte{0}}};
      if (f.cmd_id == sdk1::cmd::kHeartbeat) {
        ack.payload = {std::byte{0}, std::byte{1}, std::byte{0}, std::byte{0},
                       std::byte{0}, std::byte{0}, std::byte{0}};
      }
      replies.push_back(sdk1::encode(ack));
    }
    return replies;
  }
};

TEST(LivoxDevice, Sdk1BringUpHeartbeatStaleAndReconnect) {
  DeviceConfig config;
  config.protocol = Protocol::kSdk1;
  config.host_ip = kHostIp;
  LivoxDevice dev(config);
  FakeSdk1 lidar;
  EXPECT_EQ(dev.state(), DeviceState::kDiscovering);
  std::vector<OutgoingFrame> out;
  HostTime now(1'000'000'000);
  dev.tick(now, out);
  EXPECT_TRUE(out.empty());  // SDK1 waits for the LiDAR's broadcast
  dev.on_control_datagram(lidar.broadcast(), kLidarIp, now);
  EXPECT_EQ(dev.state(), DeviceState::kConnecting);

  // Run 10 s in 50 ms steps: the device streams data until t = 5 s, then goes silent.
  bool was_stale = false;
  for (int step = 0; step < 200; ++step) {
    now += Nanoseconds(50'000'000);
    const double t = (now.ns - 1'000'000'000) * 1e-9;
    lidar.silent = t > 5.0 && t < 8.5;
    if (!lidar.silent && dev.state() == DeviceState::kStreaming) dev.on_data(now);
    out.clear();
    dev.tick(now, out);
    for (const auto& reply : lidar.answer(out)) dev.on_control_datagram(reply, kLidarIp, now);
    if (dev.state() == DeviceState::kStale) {
      was_stale = true;
      dev.on_control_datagram(lidar.broadcast(), kLidarIp, now);  // it keeps broadcasting
    }
    if (t > 2.0 && t < 5.0) {
      EXPECT_EQ(dev.state(), DeviceState::kStreaming) << "t=" << t;
    }
  }
  EXPECT_TRUE(was_stale);
  EXPECT_EQ(dev.state(), DeviceState::kStreaming);
  EXPECT_EQ(dev.counters().stale_events, 1u);
  EXPECT_EQ(dev.counters().reconnects, 1u);
  EXPECT_GE(lidar.handshakes, 2);
  EXPECT_GE(lidar.starts, 2);
  // Heartbeats every 800 ms while connected (about 8 s of the 10 s, minus the silent gap).
  EXPECT_GE(lidar.heartbeats, 7);
  EXPECT_LE(lidar.heartbeats, 14);
}

TEST(LivoxDevice, Sdk2DiscoveryConfiguresDestinationsThenSampling) {
  DeviceConfig config;
  config.protocol = Protocol::kSdk2;
  config.host_ip = kHostIp;
  config.host_data_port = 56301;
  config.host_imu_port = 56401;
  LivoxDevice dev(config);
  std::vector<OutgoingFrame> out;
  HostTime now(5'000'000'000);
  dev.tick(now, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].dst_ip, 0xFFFFFFFFu);
  EXPECT_EQ(out[0].dst_port, 56000);
  sdk2::ControlFrame f;
  ASSERT_EQ(sdk2::parse(out[0].bytes, f), sdk2::ParseError::kNone);
  EXPECT_EQ(f.cmd_id, sdk2::cmd::kDiscovery);

  sdk2::ControlFrame ack{f.seq, sdk2::cmd::kDiscovery, 1, 1, {std::byte{0}, std::byte{9}}};
  ack.data.resize(24);
  ack.data[18] = std::byte{192};
  ack.data[19] = std::byte{168};
  ack.data[20] = std::byte{1};
  ack.data[21] = std::byte{10};
  ack.data[22] = std::byte{0x24};
  ack.data[23] = std::byte{0xDB};
  dev.on_control_datagram(sdk2::encode(ack), kLidarIp, now);
  EXPECT_EQ(dev.state(), DeviceState::kConnecting);
  EXPECT_EQ(dev.lidar_ip(), kLidarIp);

  out.clear();
  now += Nanoseconds(10'000'000);
  dev.tick(now, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].dst_port, 56100);
  ASSERT_EQ(sdk2::parse(out[0].bytes, f), sdk2::ParseError::kNone);
  EXPECT_EQ(f.cmd_id, sdk2::cmd::kSetParams);
  EXPECT_EQ(f.data[0], std::byte{3});  // three destinations in one request, like Livox-SDK2
  // ... and the point destination carries our port 56301 (0xDBED).
  bool found = false;
  for (std::size_t i = 4; i + 12 <= f.data.size(); i += 12) {
    if (f.data[i] == std::byte{0x06}) {
      found = f.data[i + 8] == std::byte{0xED} && f.data[i + 9] == std::byte{0xDB};
    }
  }
  EXPECT_TRUE(found);
  sdk2::ControlFrame set_ack{
      f.seq, sdk2::cmd::kSetParams, 1, 1, {std::byte{0}, std::byte{0}, std::byte{0}}};
  dev.on_control_datagram(sdk2::encode(set_ack), kLidarIp, now);
  EXPECT_EQ(dev.state(), DeviceState::kStarting);
  out.clear();
  dev.tick(now, out);
  ASSERT_EQ(out.size(), 1u);
  ASSERT_EQ(sdk2::parse(out[0].bytes, f), sdk2::ParseError::kNone);
  EXPECT_EQ(f.data.back(), std::byte{0x01});  // work mode SAMPLING
  dev.on_control_datagram(sdk2::encode(set_ack), kLidarIp, now);
  EXPECT_EQ(dev.state(), DeviceState::kStreaming);

  // A command that is never answered times out and is sent again.
  DeviceConfig c2 = config;
  c2.lidar_ip = kLidarIp;
  LivoxDevice quiet(c2);
  out.clear();
  quiet.tick(now, out);
  now += Nanoseconds(600'000'000);
  quiet.tick(now, out);
  now += Nanoseconds(10'000'000);
  quiet.tick(now, out);
  EXPECT_EQ(quiet.counters().timeouts, 1u);
  EXPECT_EQ(out.size(), 2u);
  // Garbage on the command port is counted, not fatal.
  std::vector<std::byte> junk(30, std::byte{0xAA});
  quiet.on_control_datagram(junk, kLidarIp, now);
  EXPECT_EQ(quiet.counters().bad_frames, 1u);
}

}  // namespace
}  // namespace livod::livox

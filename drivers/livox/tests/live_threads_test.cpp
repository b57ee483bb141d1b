// Livox supervision on the live path: a fake SDK1 LiDAR on a loopback address speaks the control
// protocol (broadcast, handshake, start sampling, heartbeat ACKs) and streams point packets to the
// port the handshake announced; it goes silent and comes back. The live source must go
// STREAMING -> STALE -> STREAMING through LivoxSupervisor, counting one reconnect, with the data
// socket, ring, capture thread and decoder untouched.

#include <gtest/gtest.h>

#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

#include "drivers/capture/live_source.hpp"
#include "drivers/livox/packets.hpp"
#include "drivers/livox/sdk1_control.hpp"
#include "drivers/livox/supervisor.hpp"
#include "drivers/registry.hpp"
#include "io/udp_socket.hpp"

namespace livod::drivers {
namespace {

using std::chrono::milliseconds;
using std::chrono::steady_clock;
namespace sdk1 = livox::sdk1;
using livox::LivoxSupervisor;
using livox::LivoxSupervisorConfig;
using namespace capture;  // NOLINT(google-build-using-namespace): a test of the capture runtime

constexpr std::uint32_t kHostIp = 0x7F000001;
constexpr std::uint32_t kAviaPointIntervalNs = 4167;

// A loopback address of its own (127.76.x.y, from the pid), so that parallel test runs never
// share the LiDAR command port 65000.
std::uint32_t fake_lidar_ip() {
  const auto pid = static_cast<std::uint32_t>(::getpid());
  return (127U << 24) | (76U << 16) | (((pid >> 8) & 0xFFU) << 8) | ((pid & 0xFFU) | 1U);
}

// The LiDAR side of SDK1, enough for bring-up: answers on <ip>:65000, broadcasts its presence to
// the host's broadcast port until handshaken, streams type-2 point packets once sampling starts.
// When `online` is false it is powered off: silent, and it forgets the connection.
class FakeSdk1Lidar {
 public:
  FakeSdk1Lidar(std::uint32_t ip, std::uint16_t host_broadcast_port)
      : ip_(ip),
        host_broadcast_port_(host_broadcast_port),
        socket_(io::UdpSocketConfig{.bind_address = io::format_ipv4(ip),
                                    .port = sdk1::kLidarCommandPort,
                                    .max_datagram_bytes = 2048}),
        thread_([this](const std::stop_token& stop) { run(stop); }) {}

  std::atomic<bool> online{true};
  std::atomic<int> handshakes{0};
  std::atomic<int> starts{0};
  std::atomic<int> heartbeats{0};
  std::atomic<std::uint64_t> packets_sent{0};

  struct Announced {
    std::uint32_t host_ip = 0;
    std::uint16_t data_port = 0;
    std::uint16_t cmd_port = 0;
    std::uint16_t imu_port = 0;
  };
  Announced announced() const {
    const std::lock_guard lock(mutex_);
    return announced_;
  }

  void stop() {
    thread_.request_stop();
    thread_.join();
  }

 private:
  std::vector<std::byte> broadcast() const {
    sdk1::ControlFrame f{sdk1::PacketType::kMsg, 0, 0, sdk1::cmd::kBroadcast, {}};
    for (const char c : std::string("3GGDJ6K00100101")) f.payload.push_back(std::byte(c));
    f.payload.insert(f.payload.end(), {std::byte{0}, std::byte{7}, std::byte{0}, std::byte{0}});
    return sdk1::encode(f);
  }

  void answer(const io::ReceivedDatagram& d) {
    sdk1::ControlFrame f;
    if (sdk1::parse(d.payload, f) != sdk1::ParseError::kNone) return;
    sdk1::ControlFrame ack{sdk1::PacketType::kAck, f.seq, f.cmd_set, f.cmd_id, {std::byte{0}}};
    if (f.cmd_set == 0 && f.cmd_id == sdk1::cmd::kHandshake && f.payload.size() == 10) {
      const auto u16 = [&](std::size_t at) {
        return static_cast<std::uint16_t>(std::to_integer<unsigned>(f.payload[at]) |
                                          (std::to_integer<unsigned>(f.payload[at + 1]) << 8));
      };
      Announced a;
      for (std::size_t i = 0; i < 4; ++i) {
        a.host_ip = (a.host_ip << 8) | std::to_integer<std::uint32_t>(f.payload[i]);
      }
      a.data_port = u16(4);
      a.cmd_port = u16(6);
      a.imu_port = u16(8);
      {
        const std::lock_guard lock(mutex_);
        announced_ = a;
      }
      connected_ = true;
      ++handshakes;
    } else if (f.cmd_set == 0 && f.cmd_id == sdk1::cmd::kSampling) {
      sampling_ = !f.payload.empty() && f.payload[0] == std::byte{1};
      ++starts;
    } else if (f.cmd_set == 0 && f.cmd_id == sdk1::cmd::kHeartbeat) {
      ack.payload = {std::byte{0}, std::byte{1}, std::byte{0}, std::byte{0},
                     std::byte{0}, std::byte{0}, std::byte{0}};
      ++heartbeats;
    } else {
      return;
    }
    socket_.send_to(d.src_ip, d.src_port, sdk1::encode(ack));
  }

  void send_points() {
    livox::Sdk1Header h;
    h.data_type = 2;
    h.timestamp_type = 0;
    h.timestamp = sensor_time_ns_;
    std::array<livox::LivoxPoint, 96> points{};
    for (std::size_t i = 0; i < points.size(); ++i) {
      points[i].x = 5.0F + 0.01F * static_cast<float>(i);
      points[i].y = -1.0F;
      points[i].z = 0.25F;
      points[i].reflectivity = 40;
      points[i].valid = true;
    }
    const Announced a = announced();
    if (socket_.send_to(a.host_ip, a.data_port, livox::encode_sdk1_points(h, points))) {
      ++packets_sent;
    }
    // The sensor clock advances with the packets: the stream has no timestamp gaps.
    sensor_time_ns_ += 96ULL * kAviaPointIntervalNs;
  }

  void run(const std::stop_token& stop) {
    auto next_broadcast = steady_clock::now();
    while (!stop.stop_requested()) {
      const auto batch = socket_.receive_batch(1);
      if (!online.load()) {
        connected_ = false;  // powered off: the next power-on starts from scratch
        sampling_ = false;
        continue;
      }
      for (const auto& d : batch) answer(d);
      if (!connected_ && steady_clock::now() >= next_broadcast) {
        socket_.send_to(kHostIp, host_broadcast_port_, broadcast());
        next_broadcast = steady_clock::now() + milliseconds(100);
      }
      if (connected_ && sampling_) send_points();
    }
  }

  std::uint32_t ip_;
  std::uint16_t host_broadcast_port_;
  io::UdpSocket socket_;
  mutable std::mutex mutex_;
  Announced announced_;  // guarded by mutex_
  bool connected_ = false;
  bool sampling_ = false;
  std::uint64_t sensor_time_ns_ = 1'000'000'000;
  std::jthread thread_;  // last
};

TEST(LivoxLive, SilentLidarGoesStaleAndIsReconnectedWithoutRestartingTheSource) {
  LiveSourceConfig source_config;
  source_config.name = "avia";
  source_config.stale_after = Nanoseconds(400'000'000);
  UdpStreamConfig data;
  data.name = "data";
  data.socket.bind_address = "127.0.0.1";
  data.socket.max_datagram_bytes = 1500;
  data.ring_capacity = 4096;
  data.thread.reported_port = 56001;
  source_config.streams.push_back(data);
  LiveSource source(source_config, make_decoder(DecoderConfig{.model = "AVIA"}));

  LivoxSupervisorConfig supervisor_config;
  supervisor_config.bind_address = "127.0.0.1";
  supervisor_config.broadcast_port = 0;  // ephemeral: the fake is told where to broadcast
  supervisor_config.device.protocol = livox::Protocol::kSdk1;
  supervisor_config.device.host_ip = kHostIp;
  supervisor_config.device.host_cmd_port = 0;  // filled in from the bound sockets
  supervisor_config.device.host_data_port = 0;
  supervisor_config.device.host_imu_port = 0;
  supervisor_config.device.heartbeat_period = Nanoseconds(200'000'000);
  supervisor_config.device.command_timeout = Nanoseconds(1'000'000'000);
  supervisor_config.device.stale_after = Nanoseconds(600'000'000);
  LivoxSupervisor supervisor(supervisor_config, {&source.stream(0)});
  ASSERT_TRUE(supervisor.broadcast_port().has_value());
  EXPECT_EQ(supervisor.device_config().host_data_port, source.stream(0).local_port());
  EXPECT_EQ(supervisor.device_config().host_cmd_port, supervisor.command_port());

  FakeSdk1Lidar lidar(fake_lidar_ip(), *supervisor.broadcast_port());

  std::vector<livox::DeviceState> states;
  std::uint64_t scans = 0;
  std::uint64_t scan_points = 0;
  DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& s) {
    ++scans;
    scan_points += s.size();
  };
  SourceHealth health;
  // Runs the consumer (this thread is the scheduler) until `done` or a generous deadline.
  const auto run_until = [&](auto done, const char* what) {
    const auto deadline = steady_clock::now() + std::chrono::seconds(20);
    auto next_health = steady_clock::now();
    while (steady_clock::now() < deadline) {
      source.consumer().poll(sinks);
      const livox::DeviceState s = supervisor.state();
      if (states.empty() || states.back() != s) states.push_back(s);
      if (steady_clock::now() >= next_health) {
        health = source.update_health(host_now());
        supervisor.annotate(health);
        next_health += milliseconds(50);
      }
      if (done()) return;
      std::this_thread::sleep_for(milliseconds(2));
    }
    ADD_FAILURE() << "timed out waiting for " << what;
  };
  const auto decoded = [&] { return source.consumer().counters().packets; };

  // 1. Bring-up from the LiDAR's broadcast; data flows.
  run_until([&] { return supervisor.state() == livox::DeviceState::kStreaming && decoded() > 300; },
            "streaming");
  const FakeSdk1Lidar::Announced announced = lidar.announced();
  EXPECT_EQ(announced.host_ip, kHostIp);
  EXPECT_EQ(announced.data_port, source.stream(0).local_port());
  EXPECT_EQ(announced.cmd_port, supervisor.command_port());
  EXPECT_EQ(announced.imu_port, source.stream(0).local_port());

  // 2. Power off: no data, no heartbeat ACKs -> STALE (device and stream health).
  lidar.online = false;
  run_until(
      [&] {
        return supervisor.state() == livox::DeviceState::kStale &&
               health.streams[0].state == StreamState::kStale;
      },
      "stale");
  supervisor.annotate(health);
  EXPECT_EQ(health.device_state, "STALE");
  const std::uint64_t decoded_before = decoded();

  // 3. Power on: broadcast -> handshake -> sampling -> data again.
  lidar.online = true;
  run_until(
      [&] {
        return supervisor.state() == livox::DeviceState::kStreaming &&
               decoded() > decoded_before + 300 &&
               health.streams[0].state == StreamState::kStreaming;
      },
      "streaming again");

  lidar.stop();
  supervisor.stop();
  // Drain what the LiDAR sent before it stopped.
  run_until([&] { return decoded() == lidar.packets_sent.load(); }, "the last packets");
  source.stop();
  source.consumer().flush(sinks);

  // STREAMING -> STALE -> STREAMING, in that order, exactly once.
  std::vector<livox::DeviceState> key;
  for (const auto s : states) {
    if (s == livox::DeviceState::kStreaming || s == livox::DeviceState::kStale) key.push_back(s);
  }
  EXPECT_EQ(key, (std::vector<livox::DeviceState>{livox::DeviceState::kStreaming,
                                                  livox::DeviceState::kStale,
                                                  livox::DeviceState::kStreaming}));
  const livox::DeviceCounters device = supervisor.counters();
  EXPECT_EQ(device.stale_events, 1u);
  EXPECT_EQ(device.reconnects, 1u);
  EXPECT_EQ(device.bad_frames, 0u);
  EXPECT_GE(lidar.handshakes.load(), 2);
  EXPECT_GE(lidar.starts.load(), 2);
  EXPECT_GT(lidar.heartbeats.load(), 0);
  health = source.update_health(host_now());
  supervisor.annotate(health);
  EXPECT_EQ(health.reconnects, 1u);
  EXPECT_EQ(health.streams[0].stale_events, 1u);
  EXPECT_EQ(health.streams[0].recoveries, 1u);
  // Every packet the LiDAR sent was captured and decoded by the same, never restarted, path.
  EXPECT_EQ(health.streams[0].capture.datagrams, lidar.packets_sent.load());
  EXPECT_EQ(health.streams[0].capture.kernel_drops, 0u);
  EXPECT_EQ(health.streams[0].capture.ring_overruns, 0u);
  EXPECT_EQ(health.decoder.lidar_packets, lidar.packets_sent.load());
  EXPECT_EQ(health.decoder.decode_errors, 0u);
  EXPECT_EQ(health.decoder.sequence_gaps, 0u);
  EXPECT_EQ(scan_points, 96 * lidar.packets_sent.load());
  EXPECT_GT(scans, 2u);
}

TEST(LivoxLive, UnansweredCommandsAreRetriedAndShutdownIsClean) {
  // An SDK2 LiDAR at a known (loopback) address that never answers: the supervisor keeps sending
  // its configuration request (timeouts counted), the stream goes STALE, stopping is prompt. The
  // known address avoids discovery broadcasts, which would leave the loopback interface.
  LiveSourceConfig source_config;
  source_config.name = "mid360";
  source_config.stale_after = Nanoseconds(100'000'000);
  UdpStreamConfig data;
  data.name = "data";
  data.socket.bind_address = "127.0.0.1";
  data.socket.max_datagram_bytes = 1500;
  data.ring_capacity = 64;
  source_config.streams.push_back(data);
  LiveSource source(source_config, make_decoder(DecoderConfig{.model = "MID-360"}));
  LivoxSupervisorConfig supervisor_config;
  supervisor_config.bind_address = "127.0.0.1";
  supervisor_config.device.protocol = livox::Protocol::kSdk2;
  supervisor_config.device.host_ip = kHostIp;
  supervisor_config.device.lidar_ip = fake_lidar_ip();
  supervisor_config.device.host_cmd_port = 0;
  supervisor_config.device.command_timeout = Nanoseconds(100'000'000);
  auto supervisor = std::make_unique<LivoxSupervisor>(
      supervisor_config, std::vector<const UdpStream*>{&source.stream(0)});
  const auto deadline = steady_clock::now() + std::chrono::seconds(20);
  SourceHealth health;
  while (steady_clock::now() < deadline) {
    health = source.update_health(host_now());
    supervisor->annotate(health);
    if (supervisor->counters().timeouts >= 2 && health.streams[0].state == StreamState::kStale) {
      break;
    }
    std::this_thread::sleep_for(milliseconds(10));
  }
  const livox::DeviceCounters c = supervisor->counters();
  EXPECT_GE(c.timeouts, 2u);
  EXPECT_GE(c.frames_sent, c.timeouts);  // each timeout is followed by a new request
  EXPECT_EQ(c.acks, 0u);
  EXPECT_EQ(supervisor->state(), livox::DeviceState::kConnecting);
  EXPECT_EQ(health.device_state, "CONNECTING");
  EXPECT_EQ(health.streams[0].state, StreamState::kStale);
  EXPECT_EQ(health.streams[0].stale_events, 1u);
  supervisor.reset();
  source.stop();
}

}  // namespace
}  // namespace livod::drivers

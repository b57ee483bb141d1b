#pragma once
// Livox device bring-up and supervision as a pure state machine (no sockets, no clocks): it is
// fed received control frames, data activity and the current time, and answers with the control
// frames to send. The live source owns the sockets; tests drive it directly.
//
// SDK1: broadcast (55000) -> handshake (to lidar:65000) -> start sampling; heartbeat every
//       800 ms; the device is STALE after 3 s without a heartbeat ACK or data, then re-handshakes.
// SDK2: discovery broadcast (56000, every 1 s) -> set point/IMU/state destinations -> work mode
//       SAMPLING; STALE after the data timeout, then configures again.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/time.hpp"
#include "drivers/livox/livox_decoder.hpp"

namespace livod::livox {

enum class DeviceState { kDiscovering, kConnecting, kStarting, kStreaming, kStale };
const char* to_string(DeviceState s);

struct DeviceConfig {
  Protocol protocol = Protocol::kSdk1;
  std::string broadcast_code;             // SDK1: match this device only (empty = first seen)
  std::optional<std::uint32_t> lidar_ip;  // known address: skip discovery
  std::uint32_t host_ip = 0;              // where the LiDAR must send (host order)
  std::uint16_t host_data_port = 56001;
  std::uint16_t host_cmd_port = 55501;
  std::uint16_t host_imu_port = 56001;
  std::uint16_t host_state_port = 56201;  // SDK2 status pushes
  Nanoseconds heartbeat_period{800'000'000};
  Nanoseconds command_timeout{500'000'000};
  Nanoseconds stale_after{3'000'000'000};
  Nanoseconds discovery_period{1'000'000'000};
};

struct OutgoingFrame {
  std::uint32_t dst_ip = 0;  // 0xFFFFFFFF = broadcast
  std::uint16_t dst_port = 0;
  std::vector<std::byte> bytes;
};

struct DeviceCounters {
  std::uint64_t frames_sent = 0;
  std::uint64_t acks = 0;
  std::uint64_t bad_frames = 0;  // control frames failing CRC/length checks
  std::uint64_t nacks = 0;       // ACKs with a non-zero return code
  std::uint64_t timeouts = 0;    // commands without an ACK in time
  std::uint64_t stale_events = 0;
  std::uint64_t reconnects = 0;   // times streaming was re-established after STALE
  std::uint32_t last_status = 0;  // SDK1 heartbeat status bitfield
};

class LivoxDevice {
 public:
  explicit LivoxDevice(DeviceConfig config);

  // A datagram from the LiDAR on the command/broadcast socket.
  void on_control_datagram(std::span<const std::byte> bytes, std::uint32_t src_ip, HostTime now);
  // A point or IMU packet arrived (the device is alive).
  void on_data(HostTime now);
  // Advances timers; appends frames to send.
  void tick(HostTime now, std::vector<OutgoingFrame>& out);

  [[nodiscard]] DeviceState state() const { return state_; }
  [[nodiscard]] const DeviceCounters& counters() const { return counters_; }
  [[nodiscard]] std::optional<std::uint32_t> lidar_ip() const { return lidar_ip_; }

 private:
  void send(std::vector<OutgoingFrame>& out, std::uint32_t ip, std::uint16_t port,
            std::vector<std::byte> bytes, HostTime now);
  void enter(DeviceState s, HostTime now);

  DeviceConfig config_;
  DeviceState state_ = DeviceState::kDiscovering;
  DeviceCounters counters_;
  std::optional<std::uint32_t> lidar_ip_;
  std::uint16_t lidar_cmd_port_ = 65000;
  std::uint32_t seq_ = 0;
  bool awaiting_ack_ = false;
  HostTime last_sent_{};
  HostTime last_heartbeat_{};
  HostTime last_alive_{};
  HostTime state_since_{};
  bool streamed_before_ = false;
};

}  // namespace livod::livox

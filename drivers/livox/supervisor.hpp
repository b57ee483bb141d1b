#pragma once
// Livox bring-up and reconnection on the live path: a low-priority control thread that owns the
// command socket(s) and a livox::LivoxDevice (the pure state machine), and runs it at ~20 Hz:
// received control frames go to on_control_datagram(), activity on the data streams to on_data(),
// and the frames tick() asks for are sent. A LiDAR that goes silent becomes STALE and is
// re-handshaken (SDK1: after its next broadcast, or at once when its address is configured; SDK2:
// rediscovered and reconfigured) without restarting anything: the data sockets, rings, capture
// threads and the decoder keep running.
//
// The control thread may allocate and block in poll(); it never touches the rings. It reads the
// data streams' capture counters (atomics) only.

#include <atomic>
#include <cstdint>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>
#include <vector>

#include "drivers/capture/health.hpp"
#include "drivers/capture/live_source.hpp"
#include "drivers/livox/device.hpp"
#include "io/udp_socket.hpp"

namespace livod::livox {

struct LivoxSupervisorConfig {
  // host_ip must be the address the LiDAR can reach the host at. Ports left at 0 are filled in:
  // host_cmd_port with the command socket's bound port, host_data_port / host_imu_port with the
  // data streams' ports (first stream = points, second = IMU if present).
  livox::DeviceConfig device;
  std::string bind_address = "0.0.0.0";
  // Where LiDARs announce themselves (SDK1 broadcasts to 55000). nullopt: no listener (SDK2, or a
  // configured lidar_ip); 0: an ephemeral port (tests).
  std::optional<std::uint16_t> broadcast_port;
  int tick_period_ms = 50;  // LivoxDevice timers are 0.5-1 s; 20 Hz keeps them accurate
};

class LivoxSupervisor {
 public:
  // `data_streams` carry the LiDAR's point/IMU packets; they must outlive the supervisor. Binds
  // the sockets (throws livod::Error) and starts the control thread.
  LivoxSupervisor(LivoxSupervisorConfig config,
                  std::vector<const drivers::capture::UdpStream*> data_streams);
  ~LivoxSupervisor();
  LivoxSupervisor(const LivoxSupervisor&) = delete;
  LivoxSupervisor& operator=(const LivoxSupervisor&) = delete;

  // Any thread.
  [[nodiscard]] livox::DeviceState state() const { return state_.load(std::memory_order_acquire); }
  [[nodiscard]] livox::DeviceCounters counters() const;
  [[nodiscard]] std::uint16_t command_port() const { return command_port_; }
  [[nodiscard]] std::optional<std::uint16_t> broadcast_port() const { return broadcast_port_; }
  // The device configuration in use (ports filled in).
  [[nodiscard]] const livox::DeviceConfig& device_config() const { return device_config_; }
  // Writes device_state and reconnects into a source's health.
  void annotate(drivers::capture::SourceHealth& health) const;

  // Stops and joins the control thread. Idempotent.
  void stop();

 private:
  void run(const std::stop_token& stop);
  void receive(io::UdpSocket& socket, livox::LivoxDevice& device);

  livox::DeviceConfig device_config_;
  std::vector<const drivers::capture::UdpStream*> data_streams_;
  int tick_period_ms_;
  io::UdpSocket command_socket_;
  std::optional<io::UdpSocket> broadcast_socket_;
  std::uint16_t command_port_;
  std::optional<std::uint16_t> broadcast_port_;

  std::atomic<livox::DeviceState> state_;
  mutable std::mutex counters_mutex_;
  livox::DeviceCounters counters_;  // guarded by counters_mutex_

  std::jthread thread_;  // last: started once everything else is ready
};

}  // namespace livod::livox

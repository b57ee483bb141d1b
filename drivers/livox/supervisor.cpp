#include "drivers/livox/supervisor.hpp"

#include <poll.h>

#include <array>
#include <utility>

namespace livod::livox {
namespace {

io::UdpSocketConfig control_socket_config(const std::string& address, std::uint16_t port) {
  io::UdpSocketConfig c;
  c.bind_address = address;
  c.port = port;
  c.receive_buffer_bytes = 256 * 1024;  // control traffic: a few frames per second
  c.batch_size = 8;
  c.max_datagram_bytes = 2048;  // control frames are < 1400 bytes
  c.allow_broadcast = true;     // SDK2 discovery is a broadcast
  return c;
}

}  // namespace

LivoxSupervisor::LivoxSupervisor(LivoxSupervisorConfig config,
                                 std::vector<const drivers::capture::UdpStream*> data_streams)
    : device_config_(std::move(config.device)),
      data_streams_(std::move(data_streams)),
      tick_period_ms_(config.tick_period_ms > 0 ? config.tick_period_ms : 50),
      command_socket_(control_socket_config(config.bind_address, device_config_.host_cmd_port)),
      command_port_(command_socket_.local_port()),
      state_(livox::DeviceState::kDiscovering) {
  if (config.broadcast_port) {
    broadcast_socket_.emplace(control_socket_config(config.bind_address, *config.broadcast_port));
    broadcast_port_ = broadcast_socket_->local_port();
  }
  // The handshake announces these ports to the LiDAR, so they must be the ones actually bound.
  if (device_config_.host_cmd_port == 0) device_config_.host_cmd_port = command_port_;
  if (device_config_.host_state_port == 0) device_config_.host_state_port = command_port_;
  if (!data_streams_.empty()) {
    if (device_config_.host_data_port == 0) {
      device_config_.host_data_port = data_streams_.front()->local_port();
    }
    if (device_config_.host_imu_port == 0) {
      device_config_.host_imu_port = data_streams_.back()->local_port();
    }
  }
  thread_ = std::jthread([this](const std::stop_token& stop) { run(stop); });
}

LivoxSupervisor::~LivoxSupervisor() {
  stop();
}

void LivoxSupervisor::stop() {
  if (thread_.joinable()) {
    thread_.request_stop();
    thread_.join();
  }
}

livox::DeviceCounters LivoxSupervisor::counters() const {
  const std::lock_guard lock(counters_mutex_);
  return counters_;
}

void LivoxSupervisor::annotate(drivers::capture::SourceHealth& health) const {
  health.device_state = livox::to_string(state());
  health.reconnects = counters().reconnects;
}

void LivoxSupervisor::receive(io::UdpSocket& socket, livox::LivoxDevice& device) {
  for (const io::ReceivedDatagram& d : socket.receive_batch(0)) {
    device.on_control_datagram(d.payload, d.src_ip, d.rx);
  }
}

void LivoxSupervisor::run(const std::stop_token& stop) {
  livox::LivoxDevice device(device_config_);
  std::vector<livox::OutgoingFrame> outgoing;
  std::vector<std::uint64_t> seen_datagrams(data_streams_.size(), 0);
  HostTime last_tick{};
  while (!stop.stop_requested()) {
    std::array<pollfd, 2> fds{};
    nfds_t n = 0;
    fds[n++] = pollfd{command_socket_.fd(), POLLIN, 0};
    if (broadcast_socket_) fds[n++] = pollfd{broadcast_socket_->fd(), POLLIN, 0};
    if (::poll(fds.data(), n, tick_period_ms_) > 0) {
      if ((fds[0].revents & POLLIN) != 0) receive(command_socket_, device);
      if (broadcast_socket_ && (fds[1].revents & POLLIN) != 0) receive(*broadcast_socket_, device);
    }
    // Data activity keeps the device alive (and completes a start whose ACK was lost).
    for (std::size_t i = 0; i < data_streams_.size(); ++i) {
      const drivers::capture::CaptureCounters c = data_streams_[i]->counters();
      if (c.datagrams != seen_datagrams[i]) {
        seen_datagrams[i] = c.datagrams;
        device.on_data(HostTime(c.last_rx_ns));
      }
    }
    const HostTime now = host_now();
    if (now - last_tick >= Nanoseconds(static_cast<std::int64_t>(tick_period_ms_) * 1'000'000)) {
      last_tick = now;
      outgoing.clear();
      device.tick(now, outgoing);
      for (const livox::OutgoingFrame& f : outgoing) {
        command_socket_.send_to(f.dst_ip, f.dst_port, f.bytes);
      }
    }
    state_.store(device.state(), std::memory_order_release);
    const std::lock_guard lock(counters_mutex_);
    counters_ = device.counters();
  }
}

}  // namespace livod::livox

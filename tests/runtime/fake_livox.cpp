#include "tests/runtime/fake_livox.hpp"

#include <unistd.h>

#include <chrono>
#include <optional>

#include "drivers/livox/sdk1_control.hpp"
#include "io/pcap.hpp"

namespace livod::test {
namespace {

namespace sdk1 = livox::sdk1;

io::UdpSocketConfig socket_config(std::uint32_t ip, std::uint16_t port) {
  return io::UdpSocketConfig{.bind_address = io::format_ipv4(ip),
                             .port = port,
                             .receive_buffer_bytes = 65536,
                             .batch_size = 8,
                             .max_datagram_bytes = 2048};
}

}  // namespace

std::uint32_t FakeAvia::loopback_ip() {
  const auto pid = static_cast<std::uint32_t>(::getpid());
  return (127U << 24) | (76U << 16) | (((pid >> 8) & 0xFFU) << 8) | ((pid & 0xFFU) | 1U);
}

FakeAvia::FakeAvia(std::uint32_t ip, std::filesystem::path capture)
    : ip_(ip),
      capture_(std::move(capture)),
      control_socket_(socket_config(ip, sdk1::kLidarCommandPort)),
      data_socket_(socket_config(ip, 0)),
      control_thread_([this](const std::stop_token& stop) { control(stop); }),
      stream_thread_([this](const std::stop_token& stop) { stream(stop); }) {}

FakeAvia::~FakeAvia() {
  stream_thread_.request_stop();
  control_thread_.request_stop();
  stream_thread_.join();
  control_thread_.join();
}

void FakeAvia::control(const std::stop_token& stop) {
  while (!stop.stop_requested()) {
    const auto batch = control_socket_.receive_batch(5);
    if (!online.load()) {
      const std::lock_guard lock(mutex_);
      sampling_ = false;  // powered off: the next power-on starts from scratch
      data_port_ = 0;
      continue;
    }
    for (const auto& d : batch) {
      sdk1::ControlFrame f;
      if (sdk1::parse(d.payload, f) != sdk1::ParseError::kNone) continue;
      sdk1::ControlFrame ack{sdk1::PacketType::kAck, f.seq, f.cmd_set, f.cmd_id, {std::byte{0}}};
      if (f.cmd_set == 0 && f.cmd_id == sdk1::cmd::kHandshake && f.payload.size() == 10) {
        std::uint32_t host = 0;
        for (std::size_t i = 0; i < 4; ++i) {
          host = (host << 8) | std::to_integer<std::uint32_t>(f.payload[i]);
        }
        const auto port =
            static_cast<std::uint16_t>(std::to_integer<unsigned>(f.payload[4]) |
                                       (std::to_integer<unsigned>(f.payload[5]) << 8));
        {
          const std::lock_guard lock(mutex_);
          host_ip_ = host;
          data_port_ = port;
        }
        ++handshakes;
        started_.store(true);
      } else if (f.cmd_set == 0 && f.cmd_id == sdk1::cmd::kSampling) {
        const std::lock_guard lock(mutex_);
        sampling_ = !f.payload.empty() && f.payload[0] == std::byte{1};
      } else if (f.cmd_set == 0 && f.cmd_id == sdk1::cmd::kHeartbeat) {
        ack.payload = {std::byte{0}, std::byte{1}, std::byte{0}, std::byte{0},
                       std::byte{0}, std::byte{0}, std::byte{0}};
      } else {
        continue;
      }
      control_socket_.send_to(d.src_ip, d.src_port, sdk1::encode(ack));
    }
  }
}

void FakeAvia::stream(const std::stop_token& stop) {
  while (!started_.load() && !stop.stop_requested()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  io::PcapReader reader(capture_);
  std::optional<std::int64_t> first_ns;
  const auto start = std::chrono::steady_clock::now();
  while (auto d = reader.next()) {
    if (stop.stop_requested()) return;
    if (!first_ns) first_ns = d->capture_time_ns;
    std::this_thread::sleep_until(start + std::chrono::nanoseconds(d->capture_time_ns - *first_ns));
    std::uint32_t host = 0;
    std::uint16_t port = 0;
    bool sampling = false;
    {
      const std::lock_guard lock(mutex_);
      host = host_ip_;
      port = data_port_;
      sampling = sampling_;
    }
    if (!online.load() || !sampling || port == 0) {
      ++lost;
      continue;
    }
    if (data_socket_.send_to(host, port, d->payload)) ++sent;
  }
  finished.store(true);
}

}  // namespace livod::test

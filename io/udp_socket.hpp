#pragma once
// A UDP receive socket for one sensor stream, in the style of a capture thread's only I/O:
// recvmmsg() batches, kernel receive timestamps (SO_TIMESTAMPNS, converted to CLOCK_MONOTONIC),
// the kernel's drop counter (SO_RXQ_OVFL), a configurable receive buffer, optional multicast
// membership and truncation detection. No allocation after open(); no logging.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/realtime_offset.hpp"
#include "core/time.hpp"

namespace livod::io {

struct UdpSocketConfig {
  std::string bind_address = "0.0.0.0";
  std::uint16_t port = 0;       // 0 = let the kernel choose (see local_port())
  std::string multicast_group;  // empty = unicast/broadcast only
  std::string multicast_interface = "0.0.0.0";
  int receive_buffer_bytes = 8 * 1024 * 1024;  // SO_RCVBUF request (the kernel may cap it)
  std::size_t batch_size = 64;                 // datagrams per recvmmsg call
  std::size_t max_datagram_bytes = 65536;      // larger datagrams are truncated and counted
  bool allow_broadcast = false;                // for control protocols that broadcast (Livox)
};

struct ReceivedDatagram {
  std::span<const std::byte> payload;  // valid until the next receive_batch()
  HostTime rx;                         // kernel receive time on CLOCK_MONOTONIC
  std::uint32_t src_ip = 0;            // host byte order
  std::uint16_t src_port = 0;
  bool truncated = false;  // datagram was larger than max_datagram_bytes
};

struct UdpSocketCounters {
  std::uint64_t datagrams = 0;
  std::uint64_t bytes = 0;
  std::uint64_t kernel_drops = 0;  // cumulative SO_RXQ_OVFL count for this socket
  std::uint64_t truncated = 0;
  std::uint64_t missing_timestamps = 0;  // datagrams without a kernel stamp (receive time used)
  std::uint64_t receive_errors = 0;
};

class UdpSocket {
 public:
  // Opens and binds the socket; throws livod::Error naming the address and the errno text.
  explicit UdpSocket(const UdpSocketConfig& config);
  ~UdpSocket();
  UdpSocket(UdpSocket&&) noexcept;
  UdpSocket& operator=(UdpSocket&&) noexcept;
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;

  // Waits up to timeout_ms for data (poll), then receives up to batch_size datagrams with one
  // recvmmsg. Returns an empty span on timeout or interruption. Never throws.
  std::span<const ReceivedDatagram> receive_batch(int timeout_ms);

  // Sends one datagram (control protocols). Returns false on error (counted).
  bool send_to(std::uint32_t dst_ip, std::uint16_t dst_port, std::span<const std::byte> payload);

  [[nodiscard]] std::uint16_t local_port() const;
  [[nodiscard]] int fd() const;
  [[nodiscard]] int effective_receive_buffer_bytes() const;
  [[nodiscard]] const UdpSocketCounters& counters() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Parses a dotted-quad IPv4 address into host byte order; throws livod::Error if invalid.
std::uint32_t parse_ipv4(const std::string& text);
std::string format_ipv4(std::uint32_t host_order_ip);

}  // namespace livod::io

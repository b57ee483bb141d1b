#pragma once
// A SocketCAN CAN_RAW socket for live CAN IMUs (sensor-protocols.md 7.1): classic and, when asked,
// CAN FD frames, kernel receive timestamps (SO_TIMESTAMPNS, CLOCK_REALTIME, converted to
// CLOCK_MONOTONIC at once), the kernel's receive-queue drop counter (SO_RXQ_OVFL), identifier
// filters in the kernel (CAN_RAW_FILTER) and error frames (CAN_RAW_ERR_FILTER: bus-off,
// error-passive, controller overflow, ...), which are counted, never decoded as data.
//
// An interface that disappears or goes down (ENETDOWN, ENODEV, POLLERR/POLLHUP) makes receive()
// report a loss; the owner closes the socket and opens it again later (DeviceThread).
//
// The interface is configured outside livod (bit rate, restart-ms, up):
//   ip link set can0 type can bitrate 500000 restart-ms 100 && ip link set can0 up

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "core/realtime_offset.hpp"
#include "drivers/imu/imu_decoder.hpp"

namespace livod::imu {

struct CanSocketConfig {
  std::string interface;           // "can0"
  bool fd_frames = false;          // also receive CAN FD frames (CAN_RAW_FD_FRAMES)
  std::vector<std::uint32_t> ids;  // kernel filter: only these identifiers (empty: all)
  bool error_frames = true;        // receive error frames (all CAN_ERR_* classes)
  int receive_buffer_bytes = 0;    // SO_RCVBUF(FORCE); 0 = the kernel default
};

// What the bus reported through error frames and the socket, cumulative.
struct CanBusCounters {
  std::uint64_t frames = 0;               // data frames received
  std::uint64_t bytes = 0;                // data bytes received
  std::uint64_t kernel_drops = 0;         // SO_RXQ_OVFL: frames the socket queue had to drop
  std::uint64_t error_frames = 0;         // error frames of any class
  std::uint64_t bus_off = 0;              // CAN_ERR_BUSOFF: the controller left the bus
  std::uint64_t error_passive = 0;        // entries into error-passive (RX or TX)
  std::uint64_t controller_overflow = 0;  // CAN_ERR_CRTL_RX/TX_OVERFLOW
  std::uint64_t restarts = 0;             // CAN_ERR_RESTARTED: controller restarted after bus-off
  std::uint64_t protocol_errors = 0;      // CAN_ERR_PROT / BUSERROR / ACK / TRX / LOSTARB
  std::uint64_t receive_errors = 0;       // recvmsg failures other than a lost interface
  std::uint64_t missing_timestamps = 0;   // frames without a kernel stamp (stamped in user space)
};

// Error-frame classification (pure; `frame.error` must be set, `id` holds the class bits).
void count_error_frame(const CanRecord& frame, CanBusCounters& counters);

// Decodes a struct can_frame / canfd_frame read from a CAN_RAW socket into `out` (rx time not
// set). False if the size is neither CAN_MTU nor CANFD_MTU or the length field is impossible.
bool parse_can_frame(std::span<const std::byte> bytes, CanRecord& out);
// The inverse (tests): a struct can_frame (classic) or canfd_frame (fd) image.
std::vector<std::byte> serialize_can_frame(const CanRecord& frame);

class CanSocket {
 public:
  // Opens, configures and binds a CAN_RAW socket. Throws livod::Error naming the interface when
  // it does not exist, is down, or the kernel has no SocketCAN.
  static CanSocket open(const CanSocketConfig& config);
  // Wraps an already connected datagram/seqpacket socket that delivers can_frame images (tests:
  // one end of a socketpair). SO_TIMESTAMPNS is enabled on it when the family supports it.
  static CanSocket adopt(int fd, std::string name);

  CanSocket(CanSocket&& other) noexcept;
  CanSocket& operator=(CanSocket&& other) noexcept;
  CanSocket(const CanSocket&) = delete;
  CanSocket& operator=(const CanSocket&) = delete;
  ~CanSocket();

  enum class Status : std::uint8_t { kOk, kLost };
  // Waits up to timeout_ms for frames and receives what is queued (at most out.size()) without
  // blocking further. `received` is the number of records filled (data and error frames; error
  // frames are also counted). kLost: the interface went away or down.
  Status receive(int timeout_ms, std::span<CanRecord> out, std::size_t& received,
                 const RealtimeToMonotonic& clock);

  [[nodiscard]] const CanBusCounters& counters() const { return counters_; }
  [[nodiscard]] const std::string& name() const { return name_; }
  [[nodiscard]] const std::string& loss_reason() const { return loss_reason_; }
  [[nodiscard]] int fd() const { return fd_; }

 private:
  CanSocket(int fd, std::string name) : fd_(fd), name_(std::move(name)) {}

  int fd_ = -1;
  std::string name_;
  CanBusCounters counters_;
  std::uint32_t last_overflow_ = 0;  // the kernel's cumulative SO_RXQ_OVFL value
  bool have_overflow_ = false;
  std::string loss_reason_;
};

}  // namespace livod::imu

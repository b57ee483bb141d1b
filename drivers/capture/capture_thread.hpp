#pragma once
// One capture thread per UDP stream (DESIGN.md "Data flow"): receives recvmmsg batches from an
// io::UdpSocket and pushes each datagram into a PacketRing; decoding happens on the consumer side.
//
// In steady state the thread never allocates, never blocks on anything but poll() (with a short
// timeout, so that a stop request is seen promptly) and never logs: it only stores counters into
// atomics that the health thread reads. A full ring drops the packet and the ring counts the
// overrun. Real-time scheduling (SCHED_FIFO) and CPU affinity are applied by the thread itself
// when configured; a refusal (no CAP_SYS_NICE, no RLIMIT_RTPRIO, CPU not in the cpuset) is
// reported in the counters, not fatal.

#include <atomic>
#include <cstdint>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>

#include "core/spsc_ring.hpp"
#include "drivers/capture/doorbell.hpp"
#include "drivers/capture/packet_ring.hpp"
#include "io/udp_socket.hpp"

namespace livod::drivers::capture {

struct CaptureThreadConfig {
  std::string thread_name;               // shown by top -H / ps (the kernel keeps 15 characters)
  std::optional<int> realtime_priority;  // SCHED_FIFO priority 1..99; nullopt = normal scheduling
  std::optional<int> cpu;                // pin the thread to this CPU; nullopt = any CPU
  int poll_timeout_ms = 20;              // bounds how long a stop request waits
  // dst_port handed downstream with each packet; 0 = the socket's bound port. A source bound to an
  // ephemeral port (tests, port remapping) reports the sensor's nominal port here.
  std::uint16_t reported_port = 0;
  // Rung after each batch that pushed packets, to wake the consumer (the daemon's scheduler)
  // when it sleeps on empty rings; nullptr = the consumer polls. Must outlive the thread.
  Doorbell* doorbell = nullptr;
};

// Outcome of a scheduling request made by the capture thread for itself.
enum class SchedulingResult : std::uint8_t { kNotRequested, kPending, kApplied, kDenied };
const char* to_string(SchedulingResult r);

// A snapshot of a capture thread's counters. Fields are read one by one (relaxed), so a snapshot
// taken while packets flow may mix values from consecutive batches; each field is monotonic.
struct CaptureCounters {
  std::uint64_t datagrams = 0;           // received from the socket
  std::uint64_t bytes = 0;               // payload bytes received
  std::uint64_t pushed = 0;              // handed to the ring
  std::uint64_t ring_overruns = 0;       // dropped because the ring was full
  std::uint64_t kernel_drops = 0;        // SO_RXQ_OVFL: dropped by the kernel (socket buffer full)
  std::uint64_t truncated = 0;           // datagrams longer than the slot
  std::uint64_t receive_errors = 0;      // poll/recvmmsg errors
  std::uint64_t missing_timestamps = 0;  // datagrams without a kernel stamp
  std::uint64_t wakeups = 0;             // loop iterations, idle ones included: the thread is alive
  std::int64_t last_rx_ns = 0;  // receive time (CLOCK_MONOTONIC) of the newest datagram; 0 = none
  SchedulingResult priority = SchedulingResult::kNotRequested;
  SchedulingResult affinity = SchedulingResult::kNotRequested;
  int priority_error = 0;  // errno-style code when the priority was denied
  int affinity_error = 0;
};

class CaptureThread {
 public:
  // Takes the socket over and starts the thread at once. `ring` must outlive this object.
  CaptureThread(io::UdpSocket socket, PacketRing& ring, CaptureThreadConfig config);
  // Stops and joins the thread.
  ~CaptureThread();
  CaptureThread(const CaptureThread&) = delete;
  CaptureThread& operator=(const CaptureThread&) = delete;

  // Requests a stop and joins (returns within about poll_timeout_ms). Idempotent.
  void stop();

  // Any thread.
  [[nodiscard]] CaptureCounters counters() const;
  [[nodiscard]] std::uint16_t local_port() const { return local_port_; }
  [[nodiscard]] int effective_receive_buffer_bytes() const { return receive_buffer_bytes_; }

 private:
  // Written by the capture thread only (plain load + store), read by anyone.
  struct alignas(kCacheLineBytes) Published {
    std::atomic<std::uint64_t> datagrams{0};
    std::atomic<std::uint64_t> bytes{0};
    std::atomic<std::uint64_t> pushed{0};
    std::atomic<std::uint64_t> kernel_drops{0};
    std::atomic<std::uint64_t> truncated{0};
    std::atomic<std::uint64_t> receive_errors{0};
    std::atomic<std::uint64_t> missing_timestamps{0};
    std::atomic<std::uint64_t> wakeups{0};
    std::atomic<std::int64_t> last_rx_ns{0};
    std::atomic<SchedulingResult> priority{SchedulingResult::kNotRequested};
    std::atomic<SchedulingResult> affinity{SchedulingResult::kNotRequested};
    std::atomic<int> priority_error{0};
    std::atomic<int> affinity_error{0};
  };

  void run(const std::stop_token& stop);
  void apply_scheduling();

  io::UdpSocket socket_;  // used by the capture thread only once it runs
  PacketRing& ring_;
  CaptureThreadConfig config_;
  std::uint16_t local_port_;
  std::uint16_t reported_port_;
  int receive_buffer_bytes_;
  Published published_;
  std::jthread thread_;  // last: started after every other member is ready, stopped first
};

}  // namespace livod::drivers::capture

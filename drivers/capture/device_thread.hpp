#pragma once
// The capture thread of a local device that can vanish and come back: a camera (V4L2, GigE/USB3
// Vision), a SocketCAN interface, a serial port or a USB IMU. Where CaptureThread serves a UDP
// socket that never goes away, this thread supervises a DeviceLink:
//
//   OPENING --open() ok--> STREAMING --device error, or silent for silence_timeout--> LOST
//      ^                                                                               |
//      +------------- close(); retry open() every reopen_interval ----------------------+
//
// The first open() runs on the constructing thread, so a device missing at start-up fails there
// with the link's message (which names the device) instead of being retried silently; with
// `wait_for_device` the failure is recorded instead (state OPENING, open_failures, last_error) and
// the thread keeps trying every reopen_interval (`livod run`: a robot may boot before its USB IMU
// enumerates). After that, losses are counted, reported (state, last_error) and reopened without
// restarting anything.
//
// Steady state (STREAMING): the thread only calls link.wait_and_read() with a short timeout and
// link.service(); it never allocates or logs (last_error is written under a mutex only on a
// failure). `wakeups` advances on every iteration, idle ones included, so a watchdog can tell
// "alive and idle" from "stuck".
//
// Threading: the link's open/close/wait_and_read/service run on this thread only (after the first
// open). counters() and last_error() may be called from any thread.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>

#include "core/time.hpp"
#include "drivers/capture/capture_thread.hpp"
#include "drivers/capture/doorbell.hpp"

namespace livod::drivers::capture {

enum class DeviceState : std::uint8_t { kOpening, kStreaming, kLost, kStopped };
const char* to_string(DeviceState s);

class DeviceLink {
 public:
  enum class Wait : std::uint8_t { kData, kIdle, kLost };

  virtual ~DeviceLink() = default;
  // Opens the device and starts its data flow. Throws livod::Error whose message names the
  // device and what failed ("V4L2 device /dev/video0 does not exist").
  virtual void open() = 0;
  // Releases the device. Must not throw; called after a loss and at stop (only when open).
  virtual void close() noexcept = 0;
  // Waits up to `timeout` for data and moves what arrived into the link's ring. kLost: the device
  // is gone or broken (loss_reason() says why); the thread closes and reopens it.
  virtual Wait wait_and_read(std::chrono::milliseconds timeout) = 0;
  // Once per loop iteration while streaming, on the capture thread: apply control requests,
  // refresh clock offsets, fire software triggers. Returning false reports a loss.
  virtual bool service() { return true; }
  // "V4L2 /dev/video0", "SocketCAN can0", ... for messages.
  [[nodiscard]] virtual std::string describe() const = 0;
  [[nodiscard]] virtual std::string loss_reason() const { return "device error"; }
};

struct DeviceThreadConfig {
  std::string thread_name;                     // top -H / ps (15 characters kept)
  std::optional<int> realtime_priority;        // SCHED_FIFO 1..99; nullopt = normal scheduling
  std::optional<int> cpu;                      // pin to this CPU; nullopt = any
  std::chrono::milliseconds poll_timeout{20};  // bounds how long stop() waits
  // > 0: a streaming device that delivers nothing for this long is treated as lost (a camera
  // that stopped sending); 0: only errors reported by the link are losses (a quiet CAN bus is
  // not broken).
  Nanoseconds silence_timeout{0};
  Nanoseconds reopen_interval{std::chrono::seconds(1)};
  // A first open() that fails does not throw: the thread retries it every reopen_interval (see
  // above). last_error() says why it is not open yet.
  bool wait_for_device = false;
  // Rung after every read that delivered data (wakes the consumer, e.g. the scheduler). May be
  // null.
  Doorbell* doorbell = nullptr;
};

struct DeviceThreadCounters {
  DeviceState state = DeviceState::kOpening;
  std::uint64_t opens = 0;          // successful opens (the first included)
  std::uint64_t open_failures = 0;  // failed open attempts (first ones with wait_for_device too)
  std::uint64_t losses = 0;         // STREAMING -> LOST transitions
  std::uint64_t reconnects = 0;     // successful opens after a loss (not a late first open)
  std::uint64_t wakeups = 0;        // loop iterations, idle ones included
  std::int64_t last_data_ns = 0;    // CLOCK_MONOTONIC of the newest data; 0 = none yet
  SchedulingResult priority = SchedulingResult::kNotRequested;
  SchedulingResult affinity = SchedulingResult::kNotRequested;
  int priority_error = 0;
  int affinity_error = 0;
};

class DeviceThread {
 public:
  // Opens `link` on the calling thread (its exception propagates, unless wait_for_device) and
  // starts the thread. `link` must outlive this object.
  DeviceThread(DeviceLink& link, DeviceThreadConfig config);
  ~DeviceThread();
  DeviceThread(const DeviceThread&) = delete;
  DeviceThread& operator=(const DeviceThread&) = delete;

  // Requests a stop, joins (within about poll_timeout plus one link call) and closes the link.
  // Idempotent.
  void stop();

  [[nodiscard]] DeviceThreadCounters counters() const;
  // Why the device is not streaming: the newest open failure or loss reason; cleared when data
  // flows again after a reopen.
  [[nodiscard]] std::string last_error() const;

 private:
  struct alignas(kCacheLineBytes) Published {
    std::atomic<DeviceState> state{DeviceState::kOpening};
    std::atomic<std::uint64_t> opens{0};
    std::atomic<std::uint64_t> open_failures{0};
    std::atomic<std::uint64_t> losses{0};
    std::atomic<std::uint64_t> reconnects{0};
    std::atomic<std::uint64_t> wakeups{0};
    std::atomic<std::int64_t> last_data_ns{0};
    std::atomic<SchedulingResult> priority{SchedulingResult::kNotRequested};
    std::atomic<SchedulingResult> affinity{SchedulingResult::kNotRequested};
    std::atomic<int> priority_error{0};
    std::atomic<int> affinity_error{0};
  };

  void run(const std::stop_token& stop);
  void apply_scheduling();
  void set_error(std::string message);

  DeviceLink& link_;
  DeviceThreadConfig config_;
  Published published_;
  mutable std::mutex error_mutex_;
  std::string last_error_;
  bool open_ = false;                // the link is open (capture thread after start)
  bool closed_ = false;              // stop() closed the link
  std::int64_t first_retry_ns_ = 0;  // wait_for_device: when to retry a failed first open
  std::jthread thread_;              // last: started when everything else is ready
};

}  // namespace livod::drivers::capture

#pragma once
// Thread heartbeats (DESIGN.md "Runtime"): every long-lived thread advances a counter on each turn
// of its loop, idle turns included, so that health (and the systemd watchdog) can tell "alive and
// idle" from "stuck". A capture thread's counter is its CaptureCounters::wakeups; the scheduler and
// the publisher own a Heartbeat.
//
// HeartbeatMonitor is clock-free (the caller passes `now`): it remembers when each counter last
// moved and reports its age.

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/time.hpp"

namespace livod::daemon::runtime {

class Heartbeat {
 public:
  // The owning thread, once per loop turn (a single writer: plain store).
  void beat() noexcept {
    beats_.store(beats_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  }
  // Any thread.
  [[nodiscard]] std::uint64_t beats() const noexcept {
    return beats_.load(std::memory_order_relaxed);
  }

 private:
  std::atomic<std::uint64_t> beats_{0};
};

struct ThreadBeat {
  std::string name;
  std::uint64_t beats = 0;
  Nanoseconds age{0};  // since the counter last moved (or since monitoring began)
  bool stuck = false;  // age > the monitor's limit
};

class HeartbeatMonitor {
 public:
  // A thread whose counter has not moved for longer than `stuck_after` is reported stuck.
  explicit HeartbeatMonitor(Nanoseconds stuck_after) : stuck_after_(stuck_after) {}

  // Registers a counter (read from any thread). Call before update().
  void add(std::string name, std::function<std::uint64_t()> read);

  // Samples every counter; returns one entry per registered thread.
  std::vector<ThreadBeat> update(HostTime now);
  // True when every counter moved since the previous call of advanced_since_last() (the watchdog
  // asks this before each ping). The first call compares with registration time.
  bool advanced_since_last();

 private:
  struct Entry {
    std::string name;
    std::function<std::uint64_t()> read;
    std::uint64_t last = 0;
    std::optional<HostTime> moved;  // when `last` was first seen
    std::uint64_t at_last_check = 0;
  };
  Nanoseconds stuck_after_;
  std::vector<Entry> entries_;
};

}  // namespace livod::daemon::runtime

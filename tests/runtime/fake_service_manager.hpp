#pragma once
// systemd's end of the notification protocol for tests: an AF_UNIX datagram socket bound to a
// fresh abstract address (NOTIFY_SOCKET="@..."; abstract addresses belong to the network
// namespace), read by a thread that keeps every datagram with its arrival time.

#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace livod::test {

class FakeServiceManager {
 public:
  using Clock = std::chrono::steady_clock;
  struct Message {
    Clock::time_point at;
    std::string text;  // "READY=1\nSTATUS=...", "WATCHDOG=1", ...
  };

  // Binds the socket (std::runtime_error when it cannot) and starts reading.
  FakeServiceManager();
  ~FakeServiceManager();
  FakeServiceManager(const FakeServiceManager&) = delete;
  FakeServiceManager& operator=(const FakeServiceManager&) = delete;

  // The value for NOTIFY_SOCKET.
  [[nodiscard]] const std::string& address() const { return address_; }
  // Everything received so far, in arrival order.
  [[nodiscard]] std::vector<Message> messages();
  // Waits until a message starting with `prefix` has arrived (true) or `timeout` passed.
  bool wait_for(const std::string& prefix, std::chrono::milliseconds timeout);

 private:
  int fd_ = -1;
  std::string address_;
  std::mutex mutex_;
  std::vector<Message> messages_;
  std::jthread reader_;  // last
};

}  // namespace livod::test

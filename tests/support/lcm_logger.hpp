#pragma once
// A real `lcm-logger` recording an LCM URL into a log, for tests that check what livod sends over
// udpm (run them in a private network namespace: livod_add_netns_test). The constructor returns
// only once the logger demonstrably records: it publishes probe messages on kProbeChannel until one
// shows up in the log (the multicast join appears in /proc/net/igmp a moment before the socket
// receives, so a first message sent right after the join can be lost). Readers skip kProbeChannel.

#include <chrono>
#include <filesystem>
#include <string>

#include "tests/support/process.hpp"

namespace livod::test {

class LcmLoggerProcess {
 public:
  static constexpr const char* kProbeChannel = "LIVOD_TEST_PROBE";

  // Starts `lcm-logger --lcm-url=URL LOG` (its output goes to LOG + ".txt"). Throws
  // std::runtime_error, with the logger's output, when it records nothing within `timeout`.
  LcmLoggerProcess(const std::string& url, std::filesystem::path log,
                   std::chrono::milliseconds timeout = std::chrono::seconds(5));

  // Leaves the logger `settle` to receive and flush the last messages, then stops it with SIGINT
  // as an operator would. Throws std::runtime_error when it does not exit within 3 s.
  void stop(std::chrono::milliseconds settle = std::chrono::milliseconds(500));

  [[nodiscard]] const std::filesystem::path& log() const { return log_; }

 private:
  std::filesystem::path log_;
  ChildProcess process_;
};

}  // namespace livod::test

#pragma once
// The command channel of a running livod over LCM: subscribes to livod.command_t on the command
// channel and publishes livod.command_result_t on the result channel (docs/lcm.md "Commands").
//
// No thread inside: the daemon's publisher (IO) thread polls it, so commands are handled on the
// thread that owns the map and never reach the scheduler. poll() dispatches what LCM has received
// without waiting. A message on the command channel that does not decode as livod.command_t is
// counted and dropped: there is no request id to answer it with.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "daemon/publish/command_records.hpp"

namespace lcm {
class LCM;
}

namespace livod::daemon::publish {

class LcmCommandChannel {
 public:
  // `lcm` must outlive the channel. Full channel names (suffix included).
  LcmCommandChannel(lcm::LCM& lcm, std::string command_channel, std::string result_channel);
  ~LcmCommandChannel();
  LcmCommandChannel(const LcmCommandChannel&) = delete;
  LcmCommandChannel& operator=(const LcmCommandChannel&) = delete;

  // Handles what LCM has received (at most 64 messages per call, never blocking) and appends the
  // commands among them to `out`.
  void poll(std::vector<CommandRecord>& out);
  // Returns false when LCM could not send it (counted in failed()).
  bool publish_result(const CommandResultRecord& result);

  [[nodiscard]] std::uint64_t malformed() const;
  [[nodiscard]] std::uint64_t failed() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The client side (`livod save-map`): sends `command` on LCM at `url` to `command_channel` and
// waits up to `timeout_ms` for the livod.command_result_t with its request_id on
// `result_channel`. Returns nullopt on timeout; throws livod::Error when LCM cannot start on
// `url` or the command cannot be sent.
std::optional<CommandResultRecord> send_command(const std::string& url,
                                                const std::string& command_channel,
                                                const std::string& result_channel,
                                                const CommandRecord& command, int timeout_ms);

}  // namespace livod::daemon::publish

#pragma once
// The daemon's message bus on LCM: the publisher thread's calls forwarded to a
// publish::LcmPublisher (docs/lcm.md), and the command channel (livod.command_t in,
// livod.command_result_t out) polled by the same thread. Built only when outputs.lcm is enabled.

#include <memory>

#include "daemon/config/config.hpp"
#include "daemon/runtime/publisher.hpp"

namespace lcm {
class LCM;
}

namespace livod::daemon::runtime {

class LcmBus final : public MessageBus {
 public:
  // Opens LCM on the configured URL (livod::Error naming it when LCM cannot start) and subscribes
  // to the command channel. `body_frame` names the body frame in every pose.
  LcmBus(const LcmOutputConfig& config, const std::string& body_frame);
  ~LcmBus() override;
  LcmBus(const LcmBus&) = delete;
  LcmBus& operator=(const LcmBus&) = delete;

  void publish_pose(const PoseRecord& pose) override;
  void publish_health(const HealthRecord& health) override;
  void publish_cloud(const publish::CloudRecord& cloud) override;
  void set_time_base(publish::TimeBase time_base) override;
  [[nodiscard]] std::vector<publish::ChannelCounters> channel_counters() const override;
  [[nodiscard]] std::uint64_t failures() const override;
  void poll_commands(std::vector<publish::CommandRecord>& out) override;
  void publish_command_result(const publish::CommandResultRecord& result) override;
  [[nodiscard]] std::uint64_t malformed_commands() const override;

  // The LCM instance, for subscribers and command senders in the same process (memq:// tests).
  // Messages to them are dispatched on the publisher thread, which polls the bus.
  [[nodiscard]] lcm::LCM& lcm();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Opens LCM on the configured URL (livod::Error naming it when LCM cannot start). `body_frame`
// names the body frame in every pose.
std::unique_ptr<MessageBus> make_lcm_bus(const LcmOutputConfig& config,
                                         const std::string& body_frame);

}  // namespace livod::daemon::runtime

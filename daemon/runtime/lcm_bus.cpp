#include "daemon/runtime/lcm_bus.hpp"

#include "daemon/publish/lcm_commands.hpp"
#include "daemon/publish/lcm_publisher.hpp"

namespace livod::daemon::runtime {

struct LcmBus::Impl {
  publish::LcmPublisher publisher;
  publish::LcmCommandChannel commands;
  std::uint64_t failures = 0;

  Impl(const LcmOutputConfig& config, const std::string& body_frame)
      : publisher(config, publish::Frames{"world", body_frame}),
        commands(publisher.lcm(), config.channel(config.channels.command),
                 config.channel(config.channels.command_result)) {}

  void count(bool ok) {
    if (!ok) ++failures;
  }
};

LcmBus::LcmBus(const LcmOutputConfig& config, const std::string& body_frame)
    : impl_(std::make_unique<Impl>(config, body_frame)) {}

LcmBus::~LcmBus() = default;

void LcmBus::publish_pose(const PoseRecord& pose) {
  impl_->count(impl_->publisher.publish_pose(pose));
}
void LcmBus::publish_health(const HealthRecord& health) {
  impl_->count(impl_->publisher.publish_health(health));
}
void LcmBus::publish_cloud(const publish::CloudRecord& cloud) {
  impl_->count(impl_->publisher.publish_cloud(cloud));
}
void LcmBus::set_time_base(publish::TimeBase time_base) {
  impl_->publisher.set_time_base(time_base);
}
std::vector<publish::ChannelCounters> LcmBus::channel_counters() const {
  return impl_->publisher.channel_counters();
}
std::uint64_t LcmBus::failures() const {
  return impl_->failures + impl_->commands.failed();
}
void LcmBus::poll_commands(std::vector<publish::CommandRecord>& out) {
  impl_->commands.poll(out);
}
void LcmBus::publish_command_result(const publish::CommandResultRecord& result) {
  impl_->commands.publish_result(result);
}
std::uint64_t LcmBus::malformed_commands() const {
  return impl_->commands.malformed();
}
lcm::LCM& LcmBus::lcm() {
  return impl_->publisher.lcm();
}

std::unique_ptr<MessageBus> make_lcm_bus(const LcmOutputConfig& config,
                                         const std::string& body_frame) {
  return std::make_unique<LcmBus>(config, body_frame);
}

}  // namespace livod::daemon::runtime

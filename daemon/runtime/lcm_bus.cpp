#include "daemon/runtime/lcm_bus.hpp"

#include "daemon/publish/lcm_publisher.hpp"

namespace livod::daemon::runtime {
namespace {

class LcmBus final : public MessageBus {
 public:
  LcmBus(const LcmOutputConfig& config, const std::string& body_frame)
      : publisher_(config, publish::Frames{"world", body_frame}) {}

  void publish_pose(const PoseRecord& pose) override { count(publisher_.publish_pose(pose)); }
  void publish_health(const HealthRecord& health) override {
    count(publisher_.publish_health(health));
  }
  void publish_cloud(const publish::CloudRecord& cloud) override {
    count(publisher_.publish_cloud(cloud));
  }
  void set_time_base(publish::TimeBase time_base) override { publisher_.set_time_base(time_base); }
  [[nodiscard]] std::vector<publish::ChannelCounters> channel_counters() const override {
    return publisher_.channel_counters();
  }
  [[nodiscard]] std::uint64_t failures() const override { return failures_; }

 private:
  void count(bool ok) {
    if (!ok) ++failures_;
  }
  publish::LcmPublisher publisher_;
  std::uint64_t failures_ = 0;
};

}  // namespace

std::unique_ptr<MessageBus> make_lcm_bus(const LcmOutputConfig& config,
                                         const std::string& body_frame) {
  return std::make_unique<LcmBus>(config, body_frame);
}

}  // namespace livod::daemon::runtime

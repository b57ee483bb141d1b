#include "daemon/publish/lcm_publisher.hpp"

#include <lcm/lcm-cpp.hpp>

#include <array>
#include <cstdint>
#include <exception>

#include "core/error.hpp"
#include "daemon/publish/lcm_messages.hpp"

namespace livod::daemon::publish {

namespace {

// LCM_MAX_CHANNEL_NAME_LENGTH of lcm.h.
constexpr std::size_t kMaxChannelLength = 63;

enum ChannelIndex : std::size_t { kPose, kPoseImu, kBotCore, kHealth, kCloud, kChannelCount };

struct Channel {
  ChannelCounters counters;
  bool used = false;
  std::int64_t next_sequence = 0;  // failed messages keep their number: a gap shows the loss
};

}  // namespace

struct LcmPublisher::Impl {
  LcmOutputConfig config;
  Frames frames;
  TimeBase time_base;
  lcm::LCM lcm;
  std::array<Channel, kChannelCount> channels;
  std::vector<std::uint8_t> buffer;  // encoding buffer, reused

  Impl(const LcmOutputConfig& c, Frames f) : config(c), frames(std::move(f)), lcm(c.url) {}

  // Builds (make()), encodes and publishes one message; counts the outcome. Never throws.
  template <class Make>
  bool send(ChannelIndex index, Make&& make) {
    Channel& ch = channels[index];
    try {
      const auto message = make();
      const int size = message.getEncodedSize();
      if (size < 0) throw Error("cannot size the message");
      buffer.resize(static_cast<std::size_t>(size));
      if (message.encode(buffer.data(), 0, size) != size) throw Error("cannot encode");
      if (lcm.publish(ch.counters.name, buffer.data(), static_cast<unsigned>(size)) != 0) {
        ++ch.counters.failed;
        return false;
      }
      ++ch.counters.published;
      ch.counters.bytes += static_cast<std::uint64_t>(size);
      return true;
    } catch (const std::exception&) {  // e.g. bad_alloc for a huge cloud: counted, not fatal
      ++ch.counters.failed;
      return false;
    }
  }

  std::int64_t take_sequence(ChannelIndex index) { return channels[index].next_sequence++; }
};

LcmPublisher::LcmPublisher(const LcmOutputConfig& config, Frames frames)
    : impl_(std::make_unique<Impl>(config, std::move(frames))) {
  if (!impl_->lcm.good()) {
    throw Error("cannot initialise LCM with URL '" + config.url +
                "' (malformed URL, no multicast route for udpm, or a file that cannot be opened; "
                "LCM's own message is on stderr)");
  }
  const std::array<std::pair<const std::string*, bool>, kChannelCount> names = {{
      {&config.channels.pose, true},
      {&config.channels.pose_imu, config.publish_imu_rate},
      {&config.channels.bot_core_pose, config.publish_bot_core_pose},
      {&config.channels.health, true},
      {&config.channels.cloud, config.publish_cloud},
  }};
  for (std::size_t i = 0; i < kChannelCount; ++i) {
    Channel& ch = impl_->channels[i];
    ch.used = names[i].second;
    ch.counters.name = config.channel(*names[i].first);
    if (!ch.used) continue;
    if (names[i].first->empty() || ch.counters.name.size() > kMaxChannelLength) {
      throw Error("LCM channel '" + ch.counters.name + "' is empty or longer than " +
                  std::to_string(kMaxChannelLength) + " bytes");
    }
  }
  if (config.publish_cloud && config.cloud_max_points < 1) {
    throw Error("cloud_max_points must be at least 1");
  }
}

LcmPublisher::~LcmPublisher() = default;

void LcmPublisher::set_time_base(TimeBase time_base) {
  impl_->time_base = time_base;
}
TimeBase LcmPublisher::time_base() const {
  return impl_->time_base;
}

bool LcmPublisher::publish_pose(const PoseRecord& pose) {
  Impl& m = *impl_;
  const bool imu = pose.source == PoseSource::kImuPropagated;
  if (imu && !m.config.publish_imu_rate) return true;
  const ChannelIndex index = imu ? kPoseImu : kPose;
  const std::int64_t sequence = m.take_sequence(index);
  bool ok = m.send(index, [&] { return to_lcm_pose(pose, m.frames, m.time_base, sequence); });
  // POSE_BODY follows the fastest pose livod publishes.
  if (m.config.publish_bot_core_pose && imu == m.config.publish_imu_rate) {
    ok = m.send(kBotCore, [&] { return to_bot_core_pose(pose, m.time_base); }) && ok;
  }
  return ok;
}

bool LcmPublisher::publish_health(const HealthRecord& health) {
  const std::int64_t sequence = impl_->take_sequence(kHealth);
  return impl_->send(kHealth, [&] { return to_lcm_health(health, sequence); });
}

bool LcmPublisher::publish_cloud(const CloudRecord& cloud) {
  Impl& m = *impl_;
  if (!m.config.publish_cloud) return true;
  const std::int64_t sequence = m.take_sequence(kCloud);
  return m.send(kCloud, [&] {
    return to_lcm_cloud(cloud, m.frames.world, m.time_base, sequence,
                        static_cast<std::size_t>(m.config.cloud_max_points));
  });
}

std::vector<ChannelCounters> LcmPublisher::channel_counters() const {
  std::vector<ChannelCounters> out;
  for (const Channel& ch : impl_->channels) {
    if (ch.used) out.push_back(ch.counters);
  }
  return out;
}

const std::string& LcmPublisher::url() const {
  return impl_->config.url;
}

lcm::LCM& LcmPublisher::lcm() {
  return impl_->lcm;
}

}  // namespace livod::daemon::publish

#pragma once
// Sends livod's records over LCM (docs/lcm.md): livod.pose_t on LIVOD_POSE / LIVOD_POSE_IMU,
// bot_core.pose_t on POSE_BODY, livod.health_t on LIVOD_HEALTH, livod.cloud_t on LIVOD_CLOUD, each
// channel name from the configuration plus its channel_suffix.
//
// No thread and no clock inside: the runtime's publisher thread calls it (one thread at a time;
// the object is not synchronised) and passes the times in the records. A failed publish (no route
// to the multicast group, a full socket buffer...) never throws: it is counted per channel, and
// the counters go into the health message.
//
// The generated LCM types stay out of this header (pimpl), so its users do not depend on them.

#include <memory>
#include <string>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/publish/records.hpp"

namespace lcm {
class LCM;
}

namespace livod::daemon::publish {

class LcmPublisher {
 public:
  // Opens LCM on config.url (config.enabled is the caller's business: it only constructs a
  // publisher when LCM output is on). Throws livod::Error naming the URL when LCM cannot be
  // initialised with it (a malformed URL, a udpm URL on a host without a multicast route, a
  // file:// path that cannot be opened) and when a channel name is empty or longer than LCM's
  // 63 bytes.
  LcmPublisher(const LcmOutputConfig& config, Frames frames);
  ~LcmPublisher();
  LcmPublisher(const LcmPublisher&) = delete;
  LcmPublisher& operator=(const LcmPublisher&) = delete;

  // unix = mapped + offset, for the utime/time_ns fields of poses and clouds (records.hpp).
  void set_time_base(TimeBase time_base);
  [[nodiscard]] TimeBase time_base() const;

  // A filter pose goes to the pose channel, an IMU-propagated one to the IMU-rate channel (and is
  // ignored, returning true, when publish_imu_rate is off). With publish_bot_core_pose, the pose
  // also goes out as bot_core.pose_t: the IMU-rate poses when publish_imu_rate is on, else the
  // filter poses. Returns false when a publish failed (counted).
  bool publish_pose(const PoseRecord& pose);
  // LIVOD_HEALTH. Returns false when the publish failed (counted).
  bool publish_health(const HealthRecord& health);
  // LIVOD_CLOUD, decimated to cloud_max_points; ignored (returning true) unless publish_cloud.
  bool publish_cloud(const CloudRecord& cloud);

  // One entry per channel this publisher uses (switched-off channels are left out), in the order
  // pose, pose_imu, bot_core_pose, health, cloud.
  [[nodiscard]] std::vector<ChannelCounters> channel_counters() const;

  [[nodiscard]] const std::string& url() const;
  // The LCM instance, for subscribers in the same process (memq:// tests).
  [[nodiscard]] lcm::LCM& lcm();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace livod::daemon::publish

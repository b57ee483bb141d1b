#pragma once
// The scheduler side of the daemon's outputs: copies each frame, IMU-rate pose and health snapshot
// into a pre-allocated record and hands it to the publisher thread (publisher.hpp) through
// RecordChannels, ringing its doorbell. Never blocks and never allocates per frame: when the
// publisher falls behind, records are dropped and counted (estimator health: outputs_dropped).
//
// Pose status policy (livod.pose_t.STATUS_*): OK after an update (and for the first frame, which
// seeds the map from the initialisation's pose); DEGENERATE when the update was weak along some
// direction; IMU_ONLY when a scan could not update the state (too few matches) and for IMU-rate
// poses propagated longer than imu_only_after; SENSOR_STALE, at the health rate, repeating the
// last pose while the estimator can make no new estimate: every LiDAR feeding it is STALE, or the
// STALE one carries the body IMU. One of several LiDARs STALE while another (and the body IMU)
// still streams is in that sensor's health only: the filter goes on updating with the others.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "daemon/runtime/output_sink.hpp"
#include "daemon/runtime/record_channel.hpp"
#include "daemon/runtime/records.hpp"
#include "drivers/capture/doorbell.hpp"
#include "drivers/capture/health.hpp"

namespace livod::daemon::runtime {

class Scheduler;

// The channels between the scheduler (producer) and the publisher (consumer).
struct PublisherChannels {
  struct Sizes {
    std::size_t frames = 8;
    std::size_t imu_poses = 512;
    std::size_t estimates = 8;
    std::size_t health = 4;
    std::size_t cloud_points = 0;  // registered-scan capacity per frame record; 0: not copied
  };
  explicit PublisherChannels(const Sizes& sizes);

  RecordChannel<FrameRecord> frames;
  // Filter poses published before their frame's record (OutputSink::on_estimate).
  RecordChannel<ImuPoseRecord> estimates;
  RecordChannel<ImuPoseRecord> imu_poses;
  RecordChannel<HealthRecord> health;
  drivers::capture::Doorbell doorbell;  // rung by the producer after each publish
  std::size_t cloud_points;
};

struct LiveOutputsOptions {
  bool imu_poses = true;
  // An IMU-rate pose this long after the last filter update is marked IMU_ONLY.
  Nanoseconds imu_only_after{300'000'000};
  // A recording released by the scheduler (no stream health) without events this long is STALE.
  Nanoseconds stale_after{500'000'000};
  std::string version;  // of the binary, for health
};

class LiveOutputs final : public OutputSink {
 public:
  LiveOutputs(PublisherChannels& channels, const LiveOutputsOptions& options);

  void on_frame(const FrameOutput& frame) override;
  void on_estimate(const EstimateOutput& estimate) override;
  void on_imu_pose(const ImuPoseOutput& pose) override;
  [[nodiscard]] bool wants_imu_poses() const override { return options_.imu_poses; }

  // Scheduler thread, at the health cadence: a health snapshot for the publisher. When the
  // estimator's LiDARs are STALE (see above), the last pose is published again with status
  // SENSOR_STALE.
  void publish_health(Scheduler& scheduler, HostTime now);

  [[nodiscard]] std::uint64_t dropped() const;

 private:
  // Per-sensor rate meters (points, IMU samples, scans per second), created at the first health.
  struct SensorRates {
    drivers::capture::RateMeter points{Nanoseconds(5'000'000'000)};
    drivers::capture::RateMeter imu{Nanoseconds(5'000'000'000)};
    drivers::capture::RateMeter scans{Nanoseconds(5'000'000'000)};
  };

  PublisherChannels& channels_;
  LiveOutputsOptions options_;
  HostTime started_;
  std::optional<PoseRecord> last_pose_;  // repeated (SENSOR_STALE) while the LiDAR is STALE
  std::optional<MappedTime> last_filter_t_;
  std::array<float, 1024> frame_ms_{};  // frame times since the previous health snapshot
  std::size_t frame_ms_count_ = 0;
  PoseStatus status_ = PoseStatus::kInitialising;
  bool estimate_published_ = false;  // the current frame's pose went out from on_estimate()
  double last_degeneracy_ratio_ = 0.0;
  estimator::VoxelMapStats last_map_;
  std::vector<SensorRates> rates_;
};

}  // namespace livod::daemon::runtime

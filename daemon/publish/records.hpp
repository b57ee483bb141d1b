#pragma once
// What livod publishes, as plain structs the runtime fills: no LCM type here, so the scheduler and
// the health code do not depend on generated code. daemon/publish/lcm_messages.hpp turns them into
// the LCM messages of docs/lcm.md; LcmPublisher sends them.
//
// PoseRecord is fixed-size (no string, no vector): the scheduler can hand it to the publisher
// thread through an SPSC ring without allocating. Frame names are fixed for a run and given to
// the publisher once (LcmPublisher::Frames).

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/time.hpp"

namespace livod::daemon::publish {

// How far a pose can be trusted (livod.pose_t.STATUS_*).
enum class PoseStatus : std::uint8_t {
  kInitialising,  // IMU initialisation or the first scan pending: not an estimate yet
  kOk,            // the latest filter update used a well-constrained scan
  kDegenerate,    // the latest update was degenerate (weak translation along some direction)
  kImuOnly,       // no LiDAR update for a while: IMU dead reckoning
  kSensorStale,   // the estimator's LiDAR is STALE: a repeat of the last pose, not a new one
};

// What produced a pose (livod.pose_t.SOURCE_*); also selects the channel.
enum class PoseSource : std::uint8_t {
  kFilter,         // a filter update (LIVOD_POSE), stamped with the scan end
  kImuPropagated,  // propagated through the IMU samples since the update (LIVOD_POSE_IMU)
};

// The body's pose in the world frame. "body" is the body IMU (the estimator's IMU frame).
struct PoseRecord {
  MappedTime t;         // measurement time on livod's timeline
  MappedTime filter_t;  // time of the filter update this pose is based on (== t for kFilter)
  bool has_filter_update = false;  // false before the first update (filter_t is then ignored)
  PoseSource source = PoseSource::kFilter;
  PoseStatus status = PoseStatus::kInitialising;
  Eigen::Matrix3d R_world_body = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_world_body = Eigen::Vector3d::Zero();  // m
  Eigen::Vector3d v_world = Eigen::Vector3d::Zero();       // m/s
  Eigen::Vector3d omega_body = Eigen::Vector3d::Zero();    // rad/s, bias removed
  Eigen::Vector3d accel_world = Eigen::Vector3d::Zero();   // m/s^2, gravity removed
  // Pose error covariance in the estimator's convention: rows/cols 0-2 the rotation error dtheta
  // (rad, right perturbation R = R_est * Exp(dtheta), i.e. body frame), 3-5 the position error
  // (m, world frame). pose_record_from_state() (pose_from_estimator.hpp) extracts it from P.
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
};

// Names of the frames every pose and cloud carries; fixed for a run.
struct Frames {
  std::string world = "world";
  std::string body;  // the configuration's body_frame (the body IMU)
};

// How mapped times (livod's timeline) become UNIX times in the messages: unix = mapped + offset.
// Live, mapped time is CLOCK_MONOTONIC and the runtime sets CLOCK_REALTIME - CLOCK_MONOTONIC
// (RealtimeToMonotonic::offset_ns(), core/realtime_offset.hpp) and refreshes it, e.g. at the health
// period, so that NTP corrections follow. In replay, mapped time
// is the recording's clock, already UNIX time for pcap and bag recordings: offset 0.
struct TimeBase {
  std::int64_t mapped_to_unix_ns = 0;
};

// ---- health (built once per health period, off the hot paths) ----------------------------------

// WAITING / STREAMING / STALE (livod.sensor_health_t.STATE_*), as drivers::capture::StreamState.
enum class SensorState : std::uint8_t { kWaiting, kStreaming, kStale };
// livod.sensor_health_t.CLOCK_*, as livod::SyncQuality.
enum class ClockQuality : std::uint8_t { kCoarse, kFine, kLost };

struct StreamHealthRecord {
  std::string name;  // "lidar", "imu", ...
  SensorState state = SensorState::kWaiting;
  std::int64_t last_packet_age_ns = -1;  // -1: nothing received yet
  double packets_per_s = 0.0;
  double megabits_per_s = 0.0;
  std::uint64_t packets = 0;
  std::uint64_t kernel_drops = 0;
  std::uint64_t ring_overruns = 0;
  std::uint64_t truncated = 0;
  std::uint64_t receive_errors = 0;
};

struct SensorHealthRecord {
  std::string name;  // configuration name
  std::string kind;  // driver ("ouster", "velodyne", "livox", "imu", ...)
  SensorState state = SensorState::kWaiting;
  std::int64_t last_data_age_ns = -1;  // -1: nothing received yet
  std::uint64_t stale_events = 0;
  std::uint64_t recoveries = 0;
  // Rates over the rate window.
  double packets_per_s = 0.0;
  double points_per_s = 0.0;
  double imu_per_s = 0.0;
  double scans_per_s = 0.0;
  // Losses by cause, cumulative.
  std::uint64_t kernel_drops = 0;
  std::uint64_t ring_overruns = 0;
  std::uint64_t sequence_gaps = 0;
  std::uint64_t truncated = 0;
  std::uint64_t decode_errors = 0;
  std::uint64_t receive_errors = 0;
  std::uint64_t late_points = 0;
  std::uint64_t incomplete_scans = 0;
  // Clock mapping (core/clock_domain.hpp ClockDomainStats).
  std::string clock_mode;  // "direct", "free_running", "receive_time"
  ClockQuality clock_quality = ClockQuality::kCoarse;
  std::int64_t clock_offset_ns = 0;
  double clock_skew_ppm = 0.0;
  std::int64_t clock_jitter_ns = 0;
  std::int64_t clock_delay_ns = 0;  // median residual delay above the floor
  std::uint64_t clock_resets = 0;
  std::uint64_t clock_sync_losses = 0;
  // Device supervision.
  std::string device_state;
  std::uint64_t reconnects = 0;
  std::uint64_t sensor_reinits = 0;
  std::string last_error;
  std::vector<StreamHealthRecord> streams;
};

struct EstimatorHealthRecord {
  PoseStatus status = PoseStatus::kInitialising;
  std::string init_status;  // why the IMU initialisation waits; empty once initialised
  // Frame times over the last health period; 0 without frames.
  double frame_time_p50_ms = 0.0;
  double frame_time_p99_ms = 0.0;
  double frame_time_max_ms = 0.0;
  std::uint64_t scans_in = 0;
  std::uint64_t scans_processed = 0;
  std::uint32_t scan_queue_depth = 0;
  std::uint32_t imu_queue_depth = 0;
  std::uint64_t scans_dropped_queue = 0;
  std::uint64_t scans_out_of_order = 0;
  std::uint64_t scans_before_init = 0;
  std::uint64_t imu_dropped_queue = 0;
  std::uint64_t imu_out_of_order = 0;
  std::uint64_t frames_without_update = 0;
  std::uint64_t degenerate_frames = 0;
  std::uint64_t scans_not_mapped = 0;  // matched but not inserted: no new viewpoint
  double translation_ratio = 0.0;      // of the latest frame
  std::uint64_t map_voxels = 0;
  std::uint64_t map_planes = 0;
  std::uint64_t map_points = 0;
  std::uint64_t map_bytes = 0;
  // Latency over the last health period (ms); see livod.estimator_health_t.
  double pose_latency_p50_ms = 0.0;
  double pose_latency_p99_ms = 0.0;
  double imu_pose_latency_p50_ms = 0.0;
  double imu_pose_latency_p99_ms = 0.0;
  std::uint64_t outputs_dropped = 0;
};

// livod.thread_health_t.STATE_*.
enum class ThreadState : std::uint8_t { kAlive, kStuck };

struct ThreadHealthRecord {
  std::string name;  // "scheduler", "publisher", "capture:os1/lidar", ...
  ThreadState state = ThreadState::kAlive;
  std::int64_t heartbeat_age_ns = 0;
  std::uint64_t heartbeats = 0;
  std::int64_t stuck_after_ns = 0;
};

// Counters of one LCM channel (LcmPublisher::channel_counters() gives them).
struct ChannelCounters {
  std::string name;  // full channel name, suffix included
  std::uint64_t published = 0;
  std::uint64_t failed = 0;
  std::uint64_t bytes = 0;  // encoded bytes of the messages published successfully
};

struct HealthRecord {
  // The snapshot time on two clocks, read together by the runtime.
  std::int64_t unix_time_ns = 0;  // CLOCK_REALTIME
  HostTime host_time;             // CLOCK_MONOTONIC
  std::string version;
  std::int64_t uptime_ns = 0;
  std::uint64_t rss_bytes = 0;
  EstimatorHealthRecord estimator;
  std::vector<SensorHealthRecord> sensors;
  std::vector<ThreadHealthRecord> threads;
  // Usually LcmPublisher::channel_counters() at the snapshot.
  std::vector<ChannelCounters> channels;
};

// ---- registered scan --------------------------------------------------------------------------

struct CloudPoint {
  float x = 0.0F;  // m, world frame
  float y = 0.0F;
  float z = 0.0F;
  float intensity = 0.0F;  // as the sensor reports it
};

struct CloudRecord {
  MappedTime t;                    // the scan end: the same instant as the scan's filter pose
  std::vector<CloudPoint> points;  // world frame, all of them (the publisher decimates)
};

}  // namespace livod::daemon::publish

#pragma once
// What the scheduler thread hands to the publisher thread: plain records, filled in place from a
// pre-allocated pool (record_channel.hpp), with no reference into the estimator. The publisher
// turns them into LCM messages, file lines and log lines.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "estimator/pipeline.hpp"

namespace livod::daemon::runtime {

// What a pose is worth (LIVOD_POSE status).
enum class PoseStatus : std::uint8_t {
  kInitialising,  // the filter has not started (IMU initialisation pending)
  kOk,
  kDegenerate,   // the update was weak along some direction (see the health's degeneracy)
  kImuOnly,      // no LiDAR update for this pose: propagated from IMU data only
  kSensorStale,  // the estimator's LiDAR is STALE: this is the last pose, not a new one
};
const char* to_string(PoseStatus s);

struct PoseRecord {
  std::int64_t t_ns = 0;  // measurement time on the mapped timeline (CLOCK_MONOTONIC domain)
  std::uint64_t sequence = 0;
  Eigen::Quaterniond q_world_body = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_world_body = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d omega_body = Eigen::Vector3d::Zero();  // bias-corrected, rad/s
  Eigen::Vector3d accel_body = Eigen::Vector3d::Zero();  // bias-corrected specific force, m/s^2
  // Pose covariance: rows/columns [dtheta (body frame, R_world_body = R Exp(dtheta)), dp (world)].
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  PoseStatus status = PoseStatus::kOk;
  std::int64_t rx_ns = 0;  // host receive time of the packet that produced it (latency)
};

// A filter frame. A record whose pose.status is kSensorStale repeats the last pose for LIVOD_POSE
// subscribers while the LiDAR is silent: it is published, never written as a new frame.
struct FrameRecord {
  PoseRecord pose;
  estimator::FrameReport report;
  double cpu_ms = 0.0;
  // The registered scan in the world frame (x y z), decimated to the record's capacity; kept only
  // when an output needs it (map, cloud).
  std::vector<float> xyz_world;
  std::size_t registered_points = 0;  // before decimation
};

struct SensorHealthRecord {
  std::string name;
  std::string kind;   // lidar, imu, camera
  std::string role;   // lidar + body imu, ...
  std::string state;  // WAITING, STREAMING, STALE
  double packets_per_s = 0.0;
  double points_per_s = 0.0;
  double last_event_age_s = -1.0;  // -1: never
  // Losses by cause.
  std::uint64_t kernel_drops = 0;
  std::uint64_t ring_overruns = 0;
  std::uint64_t sequence_gaps = 0;
  std::uint64_t truncated = 0;
  std::uint64_t decode_errors = 0;
  std::uint64_t late_points = 0;
  std::uint64_t scans = 0;
  std::uint64_t incomplete_scans = 0;
  std::uint64_t imu_samples = 0;
  // Clock domain.
  std::string clock_mode;
  std::string clock_quality;
  double clock_offset_s = 0.0;
  double clock_skew_ppm = 0.0;
  double clock_jitter_us = 0.0;
  std::uint64_t clock_resets = 0;
  // Supervision.
  std::string device_state;
  std::uint64_t reconnects = 0;
  std::uint64_t sensor_reinits = 0;
  std::string last_error;
};

struct EstimatorHealthRecord {
  PoseStatus status = PoseStatus::kInitialising;
  std::string init_status;
  std::uint64_t frames = 0;
  double frame_ms_p50 = 0.0;  // over the frames since the previous health record
  double frame_ms_p99 = 0.0;
  double frame_ms_max = 0.0;
  std::size_t queued_scans = 0;
  std::uint64_t scans_dropped = 0;  // estimator scan queue overflow (whole scans), cumulative
  std::uint64_t scans_before_init = 0;
  std::uint64_t degenerate_frames = 0;
  double degeneracy_ratio = 0.0;  // of the newest frame
  std::size_t map_voxels = 0;
  std::size_t map_points = 0;
  std::size_t map_bytes = 0;
  std::size_t rss_bytes = 0;
  std::uint64_t records_dropped = 0;  // outputs the publisher could not take in time
};

struct ThreadHealthRecord {
  std::string name;
  double age_s = 0.0;  // since its heartbeat last moved
  bool stuck = false;
};

struct HealthRecord {
  std::int64_t host_ns = 0;  // when it was taken (CLOCK_MONOTONIC)
  std::vector<SensorHealthRecord> sensors;
  EstimatorHealthRecord estimator;
  // Filled by the publisher thread.
  std::vector<ThreadHealthRecord> threads;
  double pose_latency_ms_p50 = 0.0;  // receive of the completing packet -> pose published
  double pose_latency_ms_p99 = 0.0;
  double imu_latency_ms_p50 = 0.0;  // receive of the IMU packet -> IMU-rate pose published
  double imu_latency_ms_p99 = 0.0;
};

// Fills a pose record from an estimator state (pose covariance: the [R, p] block of P).
void fill_pose(PoseRecord& r, std::int64_t t_ns, const estimator::State& x,
               const estimator::StateMatrix& P, const Eigen::Vector3d& omega_body,
               const Eigen::Vector3d& accel_body);

}  // namespace livod::daemon::runtime

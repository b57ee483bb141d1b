#pragma once
// Measurement groups (fast-livo2-notes.md 1.1, sync_packages): what the filter consumes in one
// step - an update time, the IMU samples up to it and the LiDAR points measured since the last
// update.
//
// Here groups are at LiDAR rate: the update time is the scan end and the points are the scan
// (FAST-LIVO2's ONLY_LIO grouping). The VIO half adds image-time groups from the same queues
// (scan recombination: points split at the image time, a LIO then a VIO update at that time) as a
// new Kind; LIO groups never wait for an image, so odometry goes on when a camera stops
// (FAST-LIVO2 defect 1).
//
// Inputs carry mapped times: every per-sensor offset has been applied once, by the sensor's clock
// domain, before anything reaches this class. Out-of-order input is dropped and counted; queues
// are bounded (the oldest entry is dropped and counted), so a stalled consumer cannot grow memory.

#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "core/measurement.hpp"

namespace livod::estimator {

struct SyncParams {
  std::size_t max_queued_scans = 20;  // 2 s at 10 Hz
  std::size_t max_queued_imu = 4000;  // 2 s at 2 kHz, 10 s at 400 Hz
};

struct MeasurementGroup {
  enum class Kind { lidar };
  Kind kind = Kind::lidar;
  MappedTime t_update;  // the scan end
  LidarScan scan;
  // Samples stamped in (previous update, t_update], in time order.
  std::vector<ImuSample> imu;
  // The first sample after t_update, when it has arrived (interpolates the last interval).
  std::optional<ImuSample> imu_after;
};

struct SyncCounters {
  std::uint64_t scans_in = 0;
  std::uint64_t scans_out_of_order = 0;  // end at or before the previous group's
  std::uint64_t scans_queue_overflow = 0;
  std::uint64_t imu_in = 0;
  std::uint64_t imu_out_of_order = 0;  // stamp at or before the previous sample's
  std::uint64_t imu_queue_overflow = 0;
  std::uint64_t groups = 0;
};

class MeasurementSync {
 public:
  explicit MeasurementSync(SyncParams params = {}) : params_(params) {}

  // The timeline starts at t (the IMU initialisation's last sample): earlier input is out of order.
  void start(MappedTime t);
  [[nodiscard]] bool started() const { return started_; }

  void add_imu(const ImuSample& sample);
  // Empty scans are ignored. The scan end is its latest point time. Taken by value: a caller that
  // no longer needs its copy moves it into the queue.
  void add_scan(LidarScan scan);

  // Moves the next complete group into `group` (IMU data reaches its update time); false when no
  // group is complete yet.
  bool next(MeasurementGroup& group);

  [[nodiscard]] const SyncCounters& counters() const { return counters_; }
  [[nodiscard]] std::size_t queued_scans() const { return scans_.size(); }
  [[nodiscard]] std::size_t queued_imu() const { return imu_.size(); }

  // The time of a scan's last point.
  [[nodiscard]] static MappedTime scan_end(const LidarScan& scan);

 private:
  struct QueuedScan {
    LidarScan scan;
    MappedTime end;
  };

  SyncParams params_;
  bool started_ = false;
  MappedTime last_update_;  // the last group's update time (or the start)
  MappedTime last_imu_;     // the newest accepted sample (or the start)
  std::deque<ImuSample> imu_;
  std::deque<QueuedScan> scans_;
  SyncCounters counters_;
};

}  // namespace livod::estimator

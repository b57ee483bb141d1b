#include "daemon/runtime/live_outputs.hpp"

#include <algorithm>

#include "daemon/publish/health_from_sources.hpp"
#include "daemon/publish/pose_from_estimator.hpp"
#include "daemon/replay/timing_report.hpp"
#include "daemon/runtime/scheduler.hpp"

namespace livod::daemon::runtime {
namespace {

// Nearest-rank percentile of the first n values (reorders them).
double percentile(float* values, std::size_t n, double q) {
  if (n == 0) return 0.0;
  const auto k = static_cast<std::size_t>(
                     std::clamp(q * static_cast<double>(n) + 0.5, 1.0, static_cast<double>(n))) -
                 1;
  std::nth_element(values, values + k, values + n);
  return values[k];
}

ImuSample sample_of(const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel) {
  ImuSample s;
  s.gyro_rad_s = gyro;
  s.accel_m_s2 = accel;
  return s;
}

}  // namespace

PublisherChannels::PublisherChannels(const Sizes& sizes)
    : frames(sizes.frames, [&](FrameRecord& r) { r.xyz_world.reserve(3 * sizes.cloud_points); }),
      estimates(sizes.estimates),
      imu_poses(sizes.imu_poses),
      health(sizes.health),
      cloud_points(sizes.cloud_points) {}

LiveOutputs::LiveOutputs(PublisherChannels& channels, const LiveOutputsOptions& options)
    : channels_(channels), options_(options), started_(host_now()) {}

namespace {

PoseStatus frame_status(std::uint64_t index, bool updated, bool degenerate) {
  // The first frame seeds the map (nothing to update against): its pose is the initialisation's.
  return index == 0   ? PoseStatus::kOk
         : !updated   ? PoseStatus::kImuOnly
         : degenerate ? PoseStatus::kDegenerate
                      : PoseStatus::kOk;
}

}  // namespace

void LiveOutputs::on_estimate(const EstimateOutput& estimate) {
  const auto& e = estimate.estimate;
  status_ = frame_status(estimate.index, e.updated, e.degeneracy.degenerate);
  last_filter_t_ = e.t;
  estimate_published_ = false;
  ImuPoseRecord* r = channels_.estimates.acquire();
  if (r == nullptr) return;  // counted; on_frame publishes the pose instead
  const ImuSample imu = sample_of(estimate.gyro_rad_s, estimate.accel_m_s2);
  r->pose = publish::pose_record_from_state(e.x, e.P, e.t, PoseSource::kFilter, status_, e.t, &imu);
  r->rx_ns = estimate.completed_rx_ns;
  last_pose_ = r->pose;
  channels_.estimates.publish(r);
  channels_.doorbell.ring();
  estimate_published_ = true;
}

void LiveOutputs::on_frame(const FrameOutput& frame) {
  const auto& o = frame.estimate;
  status_ = frame_status(frame.index, o.report.updated, o.report.degeneracy.degenerate);
  const bool pose_published = frame.estimate_sent && estimate_published_;
  estimate_published_ = false;
  last_degeneracy_ratio_ = o.report.degeneracy.translation_ratio;
  last_map_ = o.report.map;
  last_filter_t_ = o.t;
  if (frame_ms_count_ < frame_ms_.size()) {
    frame_ms_[frame_ms_count_++] = static_cast<float>(o.report.timings.total_ms);
  }

  FrameRecord* r = channels_.frames.acquire();
  if (r == nullptr) return;
  const ImuSample imu = sample_of(frame.gyro_rad_s, frame.accel_m_s2);
  r->pose = publish::pose_record_from_state(o.x, o.P, o.t, PoseSource::kFilter, status_, o.t, &imu);
  r->rx_ns = frame.completed_rx_ns;
  r->report = o.report;
  r->cpu_ms = frame.cpu_ms;
  r->registered_points = o.registered_world.size();
  r->pose_published = pose_published;
  r->xyz_world.clear();
  if (channels_.cloud_points > 0 && !o.registered_world.empty()) {
    // Evenly decimated to the record's capacity (the registered scan is spatially ordered, so a
    // stride keeps the coverage).
    const std::size_t n = o.registered_world.size();
    const std::size_t stride = (n + channels_.cloud_points - 1) / channels_.cloud_points;
    for (std::size_t i = 0; i < n; i += stride) {
      const Eigen::Vector3d& p = o.registered_world[i].p;
      r->xyz_world.push_back(static_cast<float>(p.x()));
      r->xyz_world.push_back(static_cast<float>(p.y()));
      r->xyz_world.push_back(static_cast<float>(p.z()));
    }
  }
  last_pose_ = r->pose;
  channels_.frames.publish(r);
  channels_.doorbell.ring();
}

void LiveOutputs::on_imu_pose(const ImuPoseOutput& pose) {
  ImuPoseRecord* r = channels_.imu_poses.acquire();
  if (r == nullptr) return;
  const auto& p = pose.pose;
  const PoseStatus status =
      p.since_update > options_.imu_only_after ? PoseStatus::kImuOnly : status_;
  r->pose = publish::pose_record_from_state(p.belief.x, p.belief.P, p.t, PoseSource::kImuPropagated,
                                            status, last_filter_t_, &pose.sample);
  r->rx_ns = pose.rx_ns;
  channels_.imu_poses.publish(r);
  channels_.doorbell.ring();
}

std::uint64_t LiveOutputs::dropped() const {
  return channels_.frames.dropped() + channels_.estimates.dropped() +
         channels_.imu_poses.dropped() + channels_.health.dropped();
}

void LiveOutputs::publish_health(Scheduler& scheduler, HostTime now) {
  HealthRecord* h = channels_.health.acquire();
  if (h == nullptr) return;
  h->host_time = now;
  h->unix_time_ns = 0;  // the publisher stamps it with its time base
  h->version = options_.version;
  h->uptime_ns = (now - started_).count();
  h->rss_bytes = replay::current_rss_bytes();

  const auto& sensors = scheduler.sensors();
  if (rates_.size() != sensors.size()) rates_.resize(sensors.size());
  h->sensors.resize(sensors.size());
  // SENSOR_STALE when no new estimate can come: every LiDAR is STALE, or the one whose internal IMU
  // is the body IMU (the IMU went with it). One of several LiDARs STALE is not: the others still
  // end scans and the filter updates with them (docs/estimator.md "Several LiDARs").
  std::size_t lidars = 0;
  std::size_t stale_lidars = 0;
  bool body_lidar_stale = false;
  for (std::size_t i = 0; i < sensors.size(); ++i) {
    ScheduledSensor& s = *sensors[i];
    const std::string kind(enum_name(s.config->driver));
    // A live camera maps its frames with its own clock domain (source.hpp).
    const ClockDomainStats clock = s.source->clock_stats().value_or(s.clock->domain().stats());
    const auto health = s.source->health(now);
    auto& rate = rates_[i];
    rate.scans.add(now, s.scans);
    rate.imu.add(now, s.imu_samples);
    if (health) rate.points.add(now, health->decoder.points);
    const publish::SensorRates rates{rate.points.per_second(), rate.imu.per_second(),
                                     rate.scans.per_second()};
    if (health) {
      h->sensors[i] = publish::sensor_health_record(*health, kind, &clock, rates);
    } else {
      // A recording released by the scheduler: its state follows the events it delivers.
      drivers::capture::SourceHealth derived;
      derived.name = s.config->name;
      h->sensors[i] = publish::sensor_health_record(derived, kind, &clock, rates);
      h->sensors[i].state = !s.last_event ? publish::SensorState::kWaiting
                            : now - *s.last_event > options_.stale_after
                                ? publish::SensorState::kStale
                                : publish::SensorState::kStreaming;
      h->sensors[i].last_data_age_ns = s.last_event ? (now - *s.last_event).count() : -1;
    }
    h->sensors[i].name = s.config->name;
    if (s.scans_to_estimator) {
      ++lidars;
      if (h->sensors[i].state == publish::SensorState::kStale) {
        ++stale_lidars;
        body_lidar_stale = body_lidar_stale || s.imu_to_estimator;
      }
    }
  }
  const bool lidar_stale = lidars > 0 && (stale_lidars == lidars || body_lidar_stale);

  // Not scheduler.pipeline(): an update may be running on the update thread.
  const EstimatorStatus& est = scheduler.estimator_status();
  const auto& c = est.counters;
  auto& e = h->estimator;
  e.status = !est.initialised ? PoseStatus::kInitialising
             : lidar_stale    ? PoseStatus::kSensorStale
                              : status_;
  e.init_status = est.init_status;
  e.frame_time_p50_ms = percentile(frame_ms_.data(), frame_ms_count_, 0.50);
  e.frame_time_p99_ms = percentile(frame_ms_.data(), frame_ms_count_, 0.99);
  e.frame_time_max_ms =
      frame_ms_count_ > 0
          ? *std::max_element(frame_ms_.begin(),
                              frame_ms_.begin() + static_cast<long>(frame_ms_count_))
          : 0.0;
  frame_ms_count_ = 0;
  e.scans_in = c.scans_in;
  e.scans_processed = c.scans_processed;
  e.scan_queue_depth = static_cast<std::uint32_t>(est.queued_scans);
  e.imu_queue_depth = static_cast<std::uint32_t>(est.queued_imu);
  e.scans_dropped_queue = c.scans_queue_overflow + est.held_scans_dropped;
  e.scans_out_of_order = c.scans_out_of_order;
  e.scans_before_init = c.scans_before_init;
  e.imu_dropped_queue = c.imu_queue_overflow + est.held_imu_dropped;
  e.imu_out_of_order = c.imu_out_of_order;
  e.frames_without_update = c.frames_without_update;
  e.degenerate_frames = c.degenerate_frames;
  e.scans_not_mapped = c.scans_not_mapped;
  e.translation_ratio = last_degeneracy_ratio_;
  // The map's statistics as of the frames' last refresh (a full traversal is too costly here).
  e.map_voxels = last_map_.root_voxels;
  e.map_planes = last_map_.planes;
  e.map_points = last_map_.stored_points;
  e.map_bytes = last_map_.bytes;
  e.outputs_dropped = dropped();
  channels_.health.publish(h);

  if (lidar_stale && last_pose_) {
    // Subscribers of LIVOD_POSE learn that the pose stopped: the last pose, marked stale.
    if (FrameRecord* r = channels_.frames.acquire()) {
      r->pose = *last_pose_;
      r->pose.status = PoseStatus::kSensorStale;
      r->rx_ns = 0;
      r->report = {};
      r->cpu_ms = 0.0;
      r->registered_points = 0;
      r->xyz_world.clear();
      channels_.frames.publish(r);
    }
  }
  channels_.doorbell.ring();
}

}  // namespace livod::daemon::runtime

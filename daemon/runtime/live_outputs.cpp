#include "daemon/runtime/live_outputs.hpp"

#include <algorithm>

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

const char* stream_state(const drivers::SourceHealth& h) {
  bool any_stale = false;
  bool any_streaming = false;
  for (const auto& s : h.streams) {
    any_stale = any_stale || s.state == drivers::StreamState::kStale;
    any_streaming = any_streaming || s.state == drivers::StreamState::kStreaming;
  }
  // A sensor is STREAMING when its main stream is; one silent auxiliary port (a Velodyne's
  // position port) does not make the sensor stale, its main stream does.
  if (!h.streams.empty()) return drivers::to_string(h.streams.front().state);
  return any_stale ? "STALE" : any_streaming ? "STREAMING" : "WAITING";
}

void fill_sensor(SensorHealthRecord& out, ScheduledSensor& s, HostTime now,
                 Nanoseconds stale_after) {
  out.name = s.config->name;
  out.kind = std::string(enum_name(sensor_kind(s.config->driver)));
  out.role = s.role;
  out.scans = s.scans;
  out.imu_samples = s.imu_samples;
  out.last_event_age_s = s.last_event ? to_seconds(now - *s.last_event) : -1.0;
  if (const auto h = s.source->health(now)) {
    out.state = stream_state(*h);
    out.packets_per_s = 0.0;
    out.kernel_drops = out.ring_overruns = out.truncated = 0;
    for (const auto& st : h->streams) {
      out.packets_per_s += st.packets_per_s;
      out.kernel_drops += st.capture.kernel_drops;
      out.ring_overruns += st.capture.ring_overruns;
      out.truncated += st.capture.truncated;
    }
    out.sequence_gaps = h->decoder.sequence_gaps;
    out.decode_errors = h->decoder.decode_errors;
    out.late_points = h->decoder.late_points;
    out.incomplete_scans = h->decoder.incomplete_scans;
    out.device_state = h->device_state;
    out.reconnects = h->reconnects;
    out.sensor_reinits = h->sensor_reinits;
    out.last_error = h->last_error;
  } else {
    // A recording released by the scheduler: its state follows the events it delivers.
    out.state = !s.last_event                       ? "WAITING"
                : now - *s.last_event > stale_after ? "STALE"
                                                    : "STREAMING";
  }
  const ClockDomainStats c = s.clock->domain().stats();
  out.clock_mode = std::string(to_string(c.mode));
  out.clock_quality = std::string(to_string(c.quality));
  out.clock_offset_s = to_seconds(c.offset);
  out.clock_skew_ppm = c.skew_ppm;
  out.clock_jitter_us = to_seconds(c.jitter) * 1e6;
  out.clock_resets = c.resets;
}

}  // namespace

PublisherChannels::PublisherChannels(const Sizes& sizes)
    : frames(sizes.frames, [&](FrameRecord& r) { r.xyz_world.reserve(3 * sizes.cloud_points); }),
      imu_poses(sizes.imu_poses),
      health(sizes.health),
      cloud_points(sizes.cloud_points) {}

LiveOutputs::LiveOutputs(PublisherChannels& channels, const LiveOutputsOptions& options)
    : channels_(channels), options_(options) {}

void LiveOutputs::on_frame(const FrameOutput& frame) {
  const auto& o = frame.estimate;
  // The first frame seeds the map (no update, nothing to update against): its pose is the
  // initialisation's, not dead reckoning.
  status_ = frame.index == 0                 ? PoseStatus::kOk
            : !o.report.updated              ? PoseStatus::kImuOnly
            : o.report.degeneracy.degenerate ? PoseStatus::kDegenerate
                                             : PoseStatus::kOk;
  last_degeneracy_ratio_ = o.report.degeneracy.translation_ratio;
  last_map_ = o.report.map;
  if (frame_ms_count_ < frame_ms_.size()) {
    frame_ms_[frame_ms_count_++] = static_cast<float>(o.report.timings.total_ms);
  }
  const Eigen::Vector3d omega = frame.gyro_rad_s - o.x.bias_gyro;
  const Eigen::Vector3d accel = frame.accel_m_s2 - o.x.bias_accel;

  FrameRecord* r = channels_.frames.acquire();
  if (r == nullptr) return;
  fill_pose(r->pose, o.t.ns, o.x, o.P, omega, accel);
  r->pose.sequence = frame.index;
  r->pose.status = status_;
  r->pose.rx_ns = frame.completed_rx_ns;
  r->report = o.report;
  r->cpu_ms = frame.cpu_ms;
  r->registered_points = o.registered_world.size();
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
  PoseRecord* r = channels_.imu_poses.acquire();
  if (r == nullptr) return;
  const auto& b = pose.pose.belief;
  fill_pose(*r, pose.pose.t.ns, b.x, b.P, pose.pose.omega_imu, Eigen::Vector3d::Zero());
  r->sequence = imu_sequence_++;
  r->status = pose.pose.since_update > options_.imu_only_after ? PoseStatus::kImuOnly : status_;
  r->rx_ns = pose.rx_ns;
  channels_.imu_poses.publish(r);
  channels_.doorbell.ring();
}

std::uint64_t LiveOutputs::dropped() const {
  return channels_.frames.dropped() + channels_.imu_poses.dropped() + channels_.health.dropped();
}

void LiveOutputs::publish_health(Scheduler& scheduler, HostTime now) {
  HealthRecord* h = channels_.health.acquire();
  if (h == nullptr) return;
  h->host_ns = now.ns;
  const auto& sensors = scheduler.sensors();
  h->sensors.resize(sensors.size());
  bool lidar_stale = false;
  for (std::size_t i = 0; i < sensors.size(); ++i) {
    fill_sensor(h->sensors[i], *sensors[i], now, Nanoseconds(500'000'000));
    if (sensors[i]->scans_to_estimator && h->sensors[i].state == std::string("STALE")) {
      lidar_stale = true;
    }
  }
  const auto& pipeline = scheduler.pipeline();
  const auto counters = pipeline.counters();
  auto& e = h->estimator;
  e.status = !pipeline.initialised() ? PoseStatus::kInitialising
             : lidar_stale           ? PoseStatus::kSensorStale
                                     : status_;
  e.init_status = pipeline.init_status();
  e.frames = scheduler.stats().frames;
  e.frame_ms_p50 = percentile(frame_ms_.data(), frame_ms_count_, 0.50);
  e.frame_ms_p99 = percentile(frame_ms_.data(), frame_ms_count_, 0.99);
  e.frame_ms_max = frame_ms_count_ > 0
                       ? *std::max_element(frame_ms_.begin(),
                                           frame_ms_.begin() + static_cast<long>(frame_ms_count_))
                       : 0.0;
  frame_ms_count_ = 0;
  e.queued_scans = pipeline.queued_scans();
  e.scans_dropped = counters.scans_queue_overflow;
  e.scans_before_init = counters.scans_before_init;
  e.degenerate_frames = counters.degenerate_frames;
  e.degeneracy_ratio = last_degeneracy_ratio_;
  // The map's statistics as of the frames' last refresh (a full traversal is too costly here).
  e.map_voxels = last_map_.root_voxels;
  e.map_points = last_map_.stored_points;
  e.map_bytes = last_map_.bytes;
  e.rss_bytes = replay::current_rss_bytes();
  e.records_dropped = dropped();
  channels_.health.publish(h);

  if (lidar_stale && last_pose_) {
    // Subscribers of LIVOD_POSE learn that the pose stopped: the last pose, marked stale.
    if (FrameRecord* r = channels_.frames.acquire()) {
      r->pose = *last_pose_;
      r->pose.status = PoseStatus::kSensorStale;
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

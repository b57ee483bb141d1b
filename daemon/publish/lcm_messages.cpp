#include "daemon/publish/lcm_messages.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace livod::daemon::publish {

namespace {

std::int64_t saturated(std::uint64_t v) {
  constexpr auto kMax = static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max());
  return static_cast<std::int64_t>(v > kMax ? kMax : v);
}

void copy3(const Eigen::Vector3d& v, double (&out)[3]) {
  for (int i = 0; i < 3; ++i) out[i] = v[i];
}

void copy_quaternion(const Eigen::Matrix3d& R, double (&out)[4]) {
  const Eigen::Quaterniond q = unit_quaternion(R);
  out[0] = q.w();
  out[1] = q.x();
  out[2] = q.y();
  out[3] = q.z();
}

// Little-endian bytes of a float, whatever the host's byte order (PointCloud2 says which order;
// livod always sends little-endian).
void put_float_le(float value, std::uint8_t* out) {
  const auto bits = std::bit_cast<std::uint32_t>(value);
  for (int i = 0; i < 4; ++i) out[i] = static_cast<std::uint8_t>(bits >> (8 * i));
}

::livod::point_field_t field(const char* name, std::int32_t offset) {
  ::livod::point_field_t f;
  f.name = name;
  f.offset = offset;
  f.datatype = ::livod::point_field_t::FLOAT32;
  f.count = 1;
  return f;
}

}  // namespace

std::int64_t utime_of(std::int64_t unix_ns) {
  std::int64_t us = unix_ns / 1000;
  if (unix_ns % 1000 < 0) --us;
  return us;
}

Eigen::Quaterniond unit_quaternion(const Eigen::Matrix3d& R) {
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  return q;
}

std::int8_t status_code(PoseStatus status) {
  switch (status) {
    case PoseStatus::kInitialising:
      return ::livod::pose_t::STATUS_INITIALISING;
    case PoseStatus::kOk:
      return ::livod::pose_t::STATUS_OK;
    case PoseStatus::kDegenerate:
      return ::livod::pose_t::STATUS_DEGENERATE;
    case PoseStatus::kImuOnly:
      return ::livod::pose_t::STATUS_IMU_ONLY;
    case PoseStatus::kSensorStale:
      return ::livod::pose_t::STATUS_SENSOR_STALE;
  }
  return ::livod::pose_t::STATUS_INITIALISING;
}

std::int8_t source_code(PoseSource source) {
  return source == PoseSource::kFilter ? ::livod::pose_t::SOURCE_FILTER
                                       : ::livod::pose_t::SOURCE_IMU_PROPAGATED;
}

std::int8_t state_code(SensorState state) {
  switch (state) {
    case SensorState::kWaiting:
      return ::livod::sensor_health_t::STATE_WAITING;
    case SensorState::kStreaming:
      return ::livod::sensor_health_t::STATE_STREAMING;
    case SensorState::kStale:
      return ::livod::sensor_health_t::STATE_STALE;
  }
  return ::livod::sensor_health_t::STATE_WAITING;
}

std::int8_t clock_quality_code(ClockQuality quality) {
  switch (quality) {
    case ClockQuality::kCoarse:
      return ::livod::sensor_health_t::CLOCK_COARSE;
    case ClockQuality::kFine:
      return ::livod::sensor_health_t::CLOCK_FINE;
    case ClockQuality::kLost:
      return ::livod::sensor_health_t::CLOCK_LOST;
  }
  return ::livod::sensor_health_t::CLOCK_COARSE;
}

std::int8_t thread_state_code(ThreadState state) {
  return state == ThreadState::kAlive ? ::livod::thread_health_t::STATE_ALIVE
                                      : ::livod::thread_health_t::STATE_STUCK;
}

::livod::pose_t to_lcm_pose(const PoseRecord& pose, const Frames& frames, TimeBase time_base,
                            std::int64_t sequence) {
  ::livod::pose_t m;
  m.time_ns = pose.t.ns + time_base.mapped_to_unix_ns;
  m.utime = utime_of(m.time_ns);
  m.mapped_time_ns = pose.t.ns;
  m.filter_time_ns = pose.has_filter_update ? pose.filter_t.ns + time_base.mapped_to_unix_ns : 0;
  m.sequence = sequence;
  m.source = source_code(pose.source);
  m.status = status_code(pose.status);
  m.world_frame = frames.world;
  m.body_frame = frames.body;
  copy3(pose.p_world_body, m.position);
  copy_quaternion(pose.R_world_body, m.orientation);
  copy3(pose.v_world, m.velocity);
  copy3(pose.omega_body, m.angular_velocity);
  copy3(pose.accel_world, m.acceleration);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) m.covariance[r][c] = pose.covariance(r, c);
  }
  return m;
}

::bot_core::pose_t to_bot_core_pose(const PoseRecord& pose, TimeBase time_base) {
  ::bot_core::pose_t m;
  m.utime = utime_of(pose.t.ns + time_base.mapped_to_unix_ns);
  copy3(pose.p_world_body, m.pos);
  copy3(pose.v_world, m.vel);
  copy_quaternion(pose.R_world_body, m.orientation);
  copy3(pose.R_world_body * pose.omega_body, m.rotation_rate);
  copy3(pose.accel_world, m.accel);
  return m;
}

::livod::health_t to_lcm_health(const HealthRecord& health, std::int64_t sequence) {
  ::livod::health_t m;
  m.time_ns = health.unix_time_ns;
  m.utime = utime_of(health.unix_time_ns);
  m.host_time_ns = health.host_time.ns;
  m.sequence = sequence;
  m.version = health.version;
  m.uptime_ns = health.uptime_ns;
  m.rss_bytes = saturated(health.rss_bytes);

  const EstimatorHealthRecord& e = health.estimator;
  ::livod::estimator_health_t& me = m.estimator;
  me.status = status_code(e.status);
  me.init_status = e.init_status;
  me.frame_time_p50_ms = e.frame_time_p50_ms;
  me.frame_time_p99_ms = e.frame_time_p99_ms;
  me.frame_time_max_ms = e.frame_time_max_ms;
  me.scans_in = saturated(e.scans_in);
  me.scans_processed = saturated(e.scans_processed);
  me.scan_queue_depth = static_cast<std::int32_t>(
      std::min<std::uint32_t>(e.scan_queue_depth, std::numeric_limits<std::int32_t>::max()));
  me.imu_queue_depth = static_cast<std::int32_t>(
      std::min<std::uint32_t>(e.imu_queue_depth, std::numeric_limits<std::int32_t>::max()));
  me.scans_dropped_queue = saturated(e.scans_dropped_queue);
  me.scans_out_of_order = saturated(e.scans_out_of_order);
  me.scans_before_init = saturated(e.scans_before_init);
  me.imu_dropped_queue = saturated(e.imu_dropped_queue);
  me.imu_out_of_order = saturated(e.imu_out_of_order);
  me.frames_without_update = saturated(e.frames_without_update);
  me.degenerate_frames = saturated(e.degenerate_frames);
  me.scans_not_mapped = saturated(e.scans_not_mapped);
  me.translation_ratio = e.translation_ratio;
  me.map_voxels = saturated(e.map_voxels);
  me.map_planes = saturated(e.map_planes);
  me.map_points = saturated(e.map_points);
  me.map_bytes = saturated(e.map_bytes);
  me.pose_latency_p50_ms = e.pose_latency_p50_ms;
  me.pose_latency_p99_ms = e.pose_latency_p99_ms;
  me.imu_pose_latency_p50_ms = e.imu_pose_latency_p50_ms;
  me.imu_pose_latency_p99_ms = e.imu_pose_latency_p99_ms;
  me.outputs_dropped = saturated(e.outputs_dropped);

  m.sensors.reserve(health.sensors.size());
  for (const SensorHealthRecord& s : health.sensors) {
    ::livod::sensor_health_t ms;
    ms.name = s.name;
    ms.kind = s.kind;
    ms.state = state_code(s.state);
    ms.last_data_age_ns = s.last_data_age_ns;
    ms.stale_events = saturated(s.stale_events);
    ms.recoveries = saturated(s.recoveries);
    ms.packets_per_s = s.packets_per_s;
    ms.points_per_s = s.points_per_s;
    ms.imu_per_s = s.imu_per_s;
    ms.scans_per_s = s.scans_per_s;
    ms.kernel_drops = saturated(s.kernel_drops);
    ms.ring_overruns = saturated(s.ring_overruns);
    ms.sequence_gaps = saturated(s.sequence_gaps);
    ms.truncated = saturated(s.truncated);
    ms.decode_errors = saturated(s.decode_errors);
    ms.receive_errors = saturated(s.receive_errors);
    ms.late_points = saturated(s.late_points);
    ms.incomplete_scans = saturated(s.incomplete_scans);
    ms.clock_mode = s.clock_mode;
    ms.clock_quality = clock_quality_code(s.clock_quality);
    ms.clock_offset_ns = s.clock_offset_ns;
    ms.clock_skew_ppm = s.clock_skew_ppm;
    ms.clock_jitter_ns = s.clock_jitter_ns;
    ms.clock_delay_ns = s.clock_delay_ns;
    ms.clock_resets = saturated(s.clock_resets);
    ms.clock_sync_losses = saturated(s.clock_sync_losses);
    ms.device_state = s.device_state;
    ms.reconnects = saturated(s.reconnects);
    ms.sensor_reinits = saturated(s.sensor_reinits);
    ms.last_error = s.last_error;
    ms.streams.reserve(s.streams.size());
    for (const StreamHealthRecord& st : s.streams) {
      ::livod::stream_health_t mst;
      mst.name = st.name;
      mst.state = state_code(st.state);
      mst.last_packet_age_ns = st.last_packet_age_ns;
      mst.packets_per_s = st.packets_per_s;
      mst.megabits_per_s = st.megabits_per_s;
      mst.packets = saturated(st.packets);
      mst.kernel_drops = saturated(st.kernel_drops);
      mst.ring_overruns = saturated(st.ring_overruns);
      mst.truncated = saturated(st.truncated);
      mst.receive_errors = saturated(st.receive_errors);
      ms.streams.push_back(std::move(mst));
    }
    ms.num_streams = static_cast<std::int32_t>(ms.streams.size());
    m.sensors.push_back(std::move(ms));
  }
  m.num_sensors = static_cast<std::int32_t>(m.sensors.size());

  m.threads.reserve(health.threads.size());
  for (const ThreadHealthRecord& t : health.threads) {
    ::livod::thread_health_t mt;
    mt.name = t.name;
    mt.state = thread_state_code(t.state);
    mt.heartbeat_age_ns = t.heartbeat_age_ns;
    mt.heartbeats = saturated(t.heartbeats);
    mt.stuck_after_ns = t.stuck_after_ns;
    m.threads.push_back(std::move(mt));
  }
  m.num_threads = static_cast<std::int32_t>(m.threads.size());

  m.channels.reserve(health.channels.size());
  for (const ChannelCounters& c : health.channels) {
    ::livod::channel_health_t mc;
    mc.name = c.name;
    mc.published = saturated(c.published);
    mc.failed = saturated(c.failed);
    mc.bytes = saturated(c.bytes);
    m.channels.push_back(std::move(mc));
  }
  m.num_channels = static_cast<std::int32_t>(m.channels.size());
  return m;
}

std::size_t decimated_count(std::size_t n, std::size_t max_points) {
  return n < max_points ? n : max_points;
}

std::size_t decimated_index(std::size_t i, std::size_t n, std::size_t kept) {
  // i * n fits: kept <= n and n is a point count (far below 2^32).
  return i * n / kept;
}

::livod::cloud_t to_lcm_cloud(const CloudRecord& cloud, const std::string& world_frame,
                              TimeBase time_base, std::int64_t sequence, std::size_t max_points) {
  if (max_points == 0) throw std::invalid_argument("to_lcm_cloud: max_points must be >= 1");
  constexpr std::int32_t kPointStep = 16;
  // LCM refuses messages above LCM_MAX_MESSAGE_SIZE (256 MiB); stay well below it.
  constexpr std::size_t kMaxPoints = std::size_t{1} << 24;
  max_points = std::min(max_points, kMaxPoints);
  ::livod::cloud_t m;
  m.time_ns = cloud.t.ns + time_base.mapped_to_unix_ns;
  m.utime = utime_of(m.time_ns);
  m.mapped_time_ns = cloud.t.ns;
  m.sequence = sequence;
  m.frame = world_frame;
  const std::size_t n = cloud.points.size();
  m.source_points =
      static_cast<std::int32_t>(std::min<std::size_t>(n, std::numeric_limits<std::int32_t>::max()));
  m.fields = {field("x", 0), field("y", 4), field("z", 8), field("intensity", 12)};
  m.num_fields = static_cast<std::int32_t>(m.fields.size());
  m.point_step = kPointStep;
  m.is_bigendian = false;
  const std::size_t kept = decimated_count(n, max_points);
  m.num_points = static_cast<std::int32_t>(kept);
  m.data.resize(kept * kPointStep);
  for (std::size_t i = 0; i < kept; ++i) {
    const CloudPoint& p = cloud.points[decimated_index(i, n, kept)];
    std::uint8_t* out = m.data.data() + i * kPointStep;
    put_float_le(p.x, out);
    put_float_le(p.y, out + 4);
    put_float_le(p.z, out + 8);
    put_float_le(p.intensity, out + 12);
  }
  m.data_size = static_cast<std::int32_t>(m.data.size());
  return m;
}

}  // namespace livod::daemon::publish

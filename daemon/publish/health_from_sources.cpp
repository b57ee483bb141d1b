#include "daemon/publish/health_from_sources.hpp"

#include <algorithm>

namespace livod::daemon::publish {

namespace {

// Higher is worse.
int severity(SensorState s) {
  switch (s) {
    case SensorState::kStreaming:
      return 0;
    case SensorState::kWaiting:
      return 1;
    case SensorState::kStale:
      return 2;
  }
  return 2;
}

}  // namespace

SensorState sensor_state(drivers::capture::StreamState state) {
  switch (state) {
    case drivers::capture::StreamState::kWaiting:
      return SensorState::kWaiting;
    case drivers::capture::StreamState::kStreaming:
      return SensorState::kStreaming;
    case drivers::capture::StreamState::kStale:
      return SensorState::kStale;
  }
  return SensorState::kStale;
}

ClockQuality clock_quality(SyncQuality quality) {
  switch (quality) {
    case SyncQuality::coarse:
      return ClockQuality::kCoarse;
    case SyncQuality::fine:
      return ClockQuality::kFine;
    case SyncQuality::lost:
      return ClockQuality::kLost;
  }
  return ClockQuality::kLost;
}

SensorHealthRecord sensor_health_record(const drivers::capture::SourceHealth& source,
                                        std::string kind, const ClockDomainStats* clock,
                                        const SensorRates& rates) {
  SensorHealthRecord r;
  r.name = source.name;
  r.kind = std::move(kind);
  r.state = SensorState::kWaiting;
  r.points_per_s = rates.points_per_s;
  r.imu_per_s = rates.imu_per_s;
  r.scans_per_s = rates.scans_per_s;

  bool first = true;
  for (const drivers::capture::StreamHealth& s : source.streams) {
    StreamHealthRecord st;
    st.name = s.name;
    st.state = sensor_state(s.state);
    st.last_packet_age_ns = s.last_packet_age ? s.last_packet_age->count() : -1;
    st.packets_per_s = s.packets_per_s;
    st.megabits_per_s = s.megabits_per_s;
    st.packets = s.capture.datagrams;
    st.kernel_drops = s.capture.kernel_drops;
    st.ring_overruns = s.capture.ring_overruns;
    st.truncated = s.capture.truncated;
    st.receive_errors = s.capture.receive_errors;

    if (first || severity(st.state) > severity(r.state)) r.state = st.state;
    first = false;
    if (st.last_packet_age_ns >= 0 &&
        (r.last_data_age_ns < 0 || st.last_packet_age_ns < r.last_data_age_ns)) {
      r.last_data_age_ns = st.last_packet_age_ns;
    }
    r.packets_per_s += st.packets_per_s;
    r.kernel_drops += st.kernel_drops;
    r.ring_overruns += st.ring_overruns;
    r.truncated += st.truncated;
    r.receive_errors += st.receive_errors;
    r.stale_events += s.stale_events;
    r.recoveries += s.recoveries;
    r.streams.push_back(std::move(st));
  }

  r.sequence_gaps = source.decoder.sequence_gaps;
  r.decode_errors = source.decoder.decode_errors;
  r.late_points = source.decoder.late_points;
  r.incomplete_scans = source.decoder.incomplete_scans;

  if (clock != nullptr) {
    r.clock_mode = std::string(to_string(clock->mode));
    r.clock_quality = clock_quality(clock->quality);
    r.clock_offset_ns = clock->offset.count();
    r.clock_skew_ppm = clock->skew_ppm;
    r.clock_jitter_ns = clock->jitter.count();
    r.clock_delay_ns = clock->residual_median.count();
    r.clock_resets = clock->resets;
    r.clock_sync_losses = clock->sync_losses;
  }

  r.device_state = source.device_state;
  r.reconnects = source.reconnects;
  r.sensor_reinits = source.sensor_reinits;
  r.last_error = source.last_error;
  return r;
}

}  // namespace livod::daemon::publish

#pragma once
// drivers::capture::SourceHealth + the sensor's clock statistics -> SensorHealthRecord: losses by
// cause, stream states and clock figures mapped once, here, for the 1 Hz health message.

#include <string>

#include "core/clock_domain.hpp"
#include "daemon/publish/records.hpp"
#include "drivers/capture/health.hpp"

namespace livod::daemon::publish {

// Rates the runtime measures from the decoder's cumulative counters (drivers::capture::RateMeter).
struct SensorRates {
  double points_per_s = 0.0;
  double imu_per_s = 0.0;
  double scans_per_s = 0.0;
};

[[nodiscard]] SensorState sensor_state(drivers::capture::StreamState state);
[[nodiscard]] ClockQuality clock_quality(SyncQuality quality);

// Sensor-level figures aggregate the streams: state = the worst (STALE, then WAITING, then
// STREAMING; WAITING without streams), last_data_age = the newest stream's, packet rate and
// socket/ring losses summed. `clock`: nullptr when the sensor has no clock domain yet (its clock
// fields then stay empty / zero).
[[nodiscard]] SensorHealthRecord sensor_health_record(const drivers::capture::SourceHealth& source,
                                                      std::string kind,
                                                      const ClockDomainStats* clock,
                                                      const SensorRates& rates);

}  // namespace livod::daemon::publish

#pragma once
// Puts one sensor's measurements on the common timeline: its ClockDomain (one per sensor; a LiDAR
// and its internal IMU share it, they share the clock) followed by the configured time_offset_s,
// added exactly once, after mapping.
//
// Which stream feeds the clock model: the IMU samples when the sensor has them (200 Hz, one
// sample per packet, no accumulation delay: the best (sensor time, receive time) pairs), else the
// scans. A scan is decoded only once it is complete, so its start lies up to a scan period behind
// the newest IMU sample; observing it would look like the clock stepping back. Scans are
// therefore only map()ped while IMU samples keep arriving, and observe the clock themselves once
// no IMU sample came for kImuSilence of receive time (a LiDAR without IMU, or an IMU stream that
// stopped).

#include <string>

#include "core/clock_domain.hpp"
#include "core/measurement.hpp"
#include "daemon/config/config.hpp"

namespace livod {
struct ImageFrame;  // core/image.hpp
}  // namespace livod

namespace livod::daemon::runtime {

// ClockConfig (YAML) -> ClockDomainConfig. `auto` is free_running for sensors decoded from their
// packets or frames (their stamps are a sensor clock), direct for dataset_* recordings (their
// header stamps were already put on one clock by the recording system).
ClockDomainConfig clock_domain_config(const SensorConfig& sensor);

class SensorClockMapper {
 public:
  explicit SensorClockMapper(const SensorConfig& sensor);

  // Sets stamp.mapped (the sample's sensor and host stamps must be set).
  void map_imu(ImuSample& sample);
  // Sets start.mapped; per-point offsets stay sensor-clock durations (a skew of 100 ppm changes
  // a 0.1 s scan by 10 us).
  void map_scan(LidarScan& scan);
  // Sets stamp.mapped from the frame's sensor and receive stamps (each frame observes the clock:
  // cameras have no faster stream), then trigger_time and mid_exposure from its exposure and
  // stamp_marks (core/image.hpp).
  void map_image(ImageFrame& frame);

  [[nodiscard]] const ClockDomain& domain() const { return domain_; }
  [[nodiscard]] double time_offset_s() const { return to_seconds(time_offset_); }

 private:
  MappedTime with_offset(MappedTime t) const { return t + time_offset_; }

  ClockDomain domain_;
  Nanoseconds time_offset_;
  bool have_imu_ = false;
  HostTime last_imu_host_;
};

}  // namespace livod::daemon::runtime

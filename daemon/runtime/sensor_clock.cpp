#include "daemon/runtime/sensor_clock.hpp"

#include <algorithm>

#include "core/image.hpp"

namespace livod::daemon::runtime {
namespace {

// An IMU stream silent for this long (receive time) no longer feeds the clock model; the scans
// do. Long against any IMU period or host stall, short against a recording.
constexpr Nanoseconds kImuSilence = std::chrono::seconds(1);

bool is_dataset(Driver driver) {
  return driver == Driver::dataset_lidar || driver == Driver::dataset_imu ||
         driver == Driver::dataset_camera;
}

// CAN IMUs whose protocol has no clock (Bosch MM7, custom): their decoders stamp the sensor time
// with the receive time, so there is no sensor clock to model (docs/drivers/imu.md).
bool has_no_sensor_clock(const SensorConfig& sensor) {
  return sensor.driver == Driver::can_imu && sensor.can.decoder != CanDecoder::sbg;
}

}  // namespace

ClockDomainConfig clock_domain_config(const SensorConfig& sensor) {
  ClockDomainConfig c;
  switch (sensor.clock.mode) {
    case ClockMode::automatic:
      c.mode = is_dataset(sensor.driver)     ? livod::ClockMode::direct
               : has_no_sensor_clock(sensor) ? livod::ClockMode::receive_time
                                             : livod::ClockMode::free_running;
      break;
    case ClockMode::direct:
      c.mode = livod::ClockMode::direct;
      break;
    case ClockMode::free_running:
      c.mode = livod::ClockMode::free_running;
      break;
    case ClockMode::receive_time:
      c.mode = livod::ClockMode::receive_time;
      break;
  }
  c.receive_latency = from_seconds(sensor.clock.latency_s);
  c.window = from_seconds(sensor.clock.window_s);
  c.max_skew_ppm = sensor.clock.max_skew_ppm;
  // Keep the sub-window of the hull at 0.5 s (the default 60 s / 120) for other windows, within
  // what the hull allows.
  const double bins = sensor.clock.window_s / 0.5;
  c.window_bins = static_cast<std::size_t>(std::clamp(bins, 4.0, 1024.0));
  c.min_fine_span = std::min(c.min_fine_span, c.window / 2);
  return c;
}

SensorClockMapper::SensorClockMapper(const SensorConfig& sensor)
    : domain_(clock_domain_config(sensor)), time_offset_(from_seconds(sensor.time_offset_s)) {}

void SensorClockMapper::map_imu(ImuSample& sample) {
  have_imu_ = true;
  last_imu_host_ = sample.stamp.host;
  sample.stamp.mapped = with_offset(domain_.observe(sample.stamp.sensor, sample.stamp.host));
}

void SensorClockMapper::map_scan(LidarScan& scan) {
  // receive_time has no sensor clock to map: every scan is stamped from its own receive time.
  const bool imu_feeds = have_imu_ && scan.start.host - last_imu_host_ < kImuSilence &&
                         domain_.config().mode != livod::ClockMode::receive_time;
  // Drivers stamp the scan with the sensor time of its first point and the receive time of the
  // packet holding it, back-dated to that point by the firings after it in the packet (the packet
  // leaves when its last firing is done; Livox back-dates to the scan start): no accumulation
  // latency is left for the clock model.
  const MappedTime t = imu_feeds ? domain_.map(scan.start.sensor)
                                 : domain_.observe(scan.start.sensor, scan.start.host);
  scan.start.mapped = with_offset(t);
}

void SensorClockMapper::map_image(ImageFrame& frame) {
  frame.stamp.mapped = with_offset(domain_.observe(frame.stamp.sensor, frame.stamp.host));
  set_exposure_times(frame);
}

}  // namespace livod::daemon::runtime

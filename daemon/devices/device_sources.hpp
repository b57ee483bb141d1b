#pragma once
// Live camera and IMU sources built from a sensor's configuration: what `livod run` opens for
// `driver: v4l2 | aravis | can_imu | serial_imu` with `source: {device: ...}`.
//
//   auto cam = devices::open_camera_source(sensor, config);      // throws naming sensor + device
//   // scheduler loop:  cam->poll([&](const camera::CameraFrame& f) { ... f.mid_exposure ... });
//   //   at 1 Hz:       camera::format_health(cam->update_health(host_now()))
//   auto imu = devices::open_can_imu_source(sensor, config);
//   // scheduler loop:  imu->poll([&](const ImuSample& s) { mapper.map_imu(copy of s); ... });
//
// Every source starts its capture thread in the constructor and stops it in stop() / the
// destructor (drivers/camera/camera_source.hpp, drivers/imu/imu_source.hpp for the contracts).
// By default a device that cannot be opened throws; with DeviceOpenOptions::wait_for_device (what
// `livod run` uses, runtime/live_device_sources.hpp) its capture thread keeps trying instead.
// Camera frames come out mapped onto the common timeline (the camera clock adds the sensor's
// time_offset_s); IMU samples carry sensor and host time and are mapped by the caller's clock
// domain (runtime::SensorClockMapper), in receive_time mode for IMUs without a sensor clock
// (imu_clock_mode()).

#include <memory>

#include "core/clock_domain.hpp"
#include "daemon/config/config.hpp"
#include "drivers/camera/camera_source.hpp"
#include "drivers/capture/doorbell.hpp"
#include "drivers/imu/imu_source.hpp"

namespace livod::daemon::devices {

struct DeviceOpenOptions {
  // A device that cannot be opened does not throw: the source reports why (health last_error,
  // device state OPENING) and its capture thread retries every second until it opens.
  bool wait_for_device = false;
  // Rung by the capture thread when data arrives (wakes the scheduler). May be null.
  drivers::capture::Doorbell* doorbell = nullptr;
  // Recording (`livod record`, outputs.record): the IMU's capture thread also copies what it
  // queues into this tap (daemon/record/recorder.hpp). May be null. can_tap for can_imu,
  // serial_tap (slots of at least kSerialChunkBytes) for serial_imu; camera_tap for cameras.
  SpscRing<imu::CanRecord>* can_tap = nullptr;
  drivers::capture::PacketRing* serial_tap = nullptr;
  // For a camera: slots of at least width x height x bytes per pixel (camera_frame_bytes()).
  camera::FrameRing* camera_tap = nullptr;
};

// The bytes of one frame of the sensor's configured size and pixel format (a ring slot).
std::size_t camera_frame_bytes(const SensorConfig& sensor);

// The largest read of a serial IMU's capture thread (the slot size of its rings).
inline constexpr std::size_t kSerialChunkBytes = 4096;

// The camera clock for a sensor: clock.mode auto lets the frames' clock decide (V4L2 monotonic
// stamps: direct; GenICam ticks: free-running; PTP: direct), other modes force it; latency,
// window and skew bound as configured; time_offset_s and camera.readout_s applied.
camera::CameraClockConfig camera_clock_config(const SensorConfig& sensor);

// A v4l2 or aravis sensor with a device source. Throws livod::Error "sensor 'NAME': ..." when the
// camera is missing or refuses the configuration (format, size, controls).
std::unique_ptr<camera::CameraSource> open_camera_source(const SensorConfig& sensor,
                                                         const LivodConfig& config,
                                                         const DeviceOpenOptions& options = {});

// A can_imu sensor with a device source (SocketCAN interface).
std::unique_ptr<imu::CanImuSource> open_can_imu_source(const SensorConfig& sensor,
                                                       const LivodConfig& config,
                                                       const DeviceOpenOptions& options = {});

// A serial_imu sensor with a device source (tty path or usb:VVVV:PPPP[:SERIAL]).
std::unique_ptr<imu::SerialImuSource> open_serial_imu_source(const SensorConfig& sensor,
                                                             const LivodConfig& config,
                                                             const DeviceOpenOptions& options = {});

// The clock mode an external IMU needs with clock.mode auto: free_running when its protocol
// carries a sensor clock (SBG, Xsens), receive_time otherwise (Bosch MM7, custom CAN); the
// configured mode when one is given. The same as runtime::clock_domain_config(sensor).mode, which
// the scheduler's clock domains use, live and in replay.
livod::ClockMode imu_clock_mode(const SensorConfig& sensor);

}  // namespace livod::daemon::devices

#include "daemon/devices/device_sources.hpp"

#include <algorithm>
#include <variant>

#include "core/error.hpp"
#include "daemon/devices/imu_decoders.hpp"
#include "daemon/runtime/sensor_clock.hpp"
#include "drivers/camera/aravis_camera.hpp"
#include "drivers/camera/pixel_convert.hpp"
#include "drivers/camera/v4l2_camera.hpp"

namespace livod::daemon::devices {
namespace {

const DeviceSourceConfig& device_of(const SensorConfig& sensor) {
  const auto* d = std::get_if<DeviceSourceConfig>(&sensor.source);
  if (d == nullptr) throw Error("sensor '" + sensor.name + "': not a device source");
  return *d;
}

camera::PixelFormat pixel_format(CameraPixelFormat f) {
  switch (f) {
    case CameraPixelFormat::mono8:
      return camera::PixelFormat::kMono8;
    case CameraPixelFormat::mono16:
      return camera::PixelFormat::kMono16;
    case CameraPixelFormat::bgr8:
      return camera::PixelFormat::kBgr8;
  }
  return camera::PixelFormat::kMono8;
}

drivers::capture::DeviceThreadConfig thread_config(const std::string& prefix,
                                                   const SensorConfig& sensor,
                                                   const LivodConfig& config,
                                                   const DeviceOpenOptions& options) {
  drivers::capture::DeviceThreadConfig t;
  t.thread_name = prefix + sensor.name;
  if (config.realtime.capture_priority > 0) t.realtime_priority = config.realtime.capture_priority;
  if (config.realtime.capture_cpu >= 0) t.cpu = config.realtime.capture_cpu;
  t.wait_for_device = options.wait_for_device;
  t.doorbell = options.doorbell;
  return t;
}

Nanoseconds stale_after(const LivodConfig& config) {
  return from_seconds(config.health.stale_after_s);
}

// Rethrows a device error with the sensor's name in front.
template <class F>
auto named(const SensorConfig& sensor, F&& open) {
  try {
    return open();
  } catch (const Error& e) {
    throw Error("sensor '" + sensor.name + "': " + e.what());
  }
}

}  // namespace

camera::CameraClockConfig camera_clock_config(const SensorConfig& sensor) {
  camera::CameraClockConfig c;
  c.domain = runtime::clock_domain_config(sensor);
  if (sensor.clock.mode != ClockMode::automatic) c.mode = c.domain.mode;
  c.readout = from_seconds(sensor.camera.readout_s);
  c.time_offset = from_seconds(sensor.time_offset_s);
  return c;
}

std::size_t camera_frame_bytes(const SensorConfig& sensor) {
  return static_cast<std::size_t>(std::max(sensor.camera.width, 1)) *
         static_cast<std::size_t>(std::max(sensor.camera.height, 1)) *
         static_cast<std::size_t>(
             camera::bytes_per_pixel(pixel_format(sensor.camera.pixel_format)));
}

std::unique_ptr<camera::CameraSource> open_camera_source(const SensorConfig& sensor,
                                                         const LivodConfig& config,
                                                         const DeviceOpenOptions& options) {
  const DeviceSourceConfig& device = device_of(sensor);
  const CameraConfig& cam = sensor.camera;
  camera::CameraSourceConfig sc;
  sc.name = sensor.name;
  sc.width = cam.width;
  sc.height = cam.height;
  sc.format = pixel_format(cam.pixel_format);
  sc.ring_capacity = static_cast<std::size_t>(sensor.ring_capacity);
  sc.decimation = cam.decimation;
  sc.tap = options.camera_tap;
  sc.clock = camera_clock_config(sensor);
  sc.thread = thread_config("cam:", sensor, config, options);
  sc.stale_after = stale_after(config);
  std::optional<Nanoseconds> exposure;
  if (cam.exposure_s) exposure = from_seconds(*cam.exposure_s);
  std::optional<camera::StampInstant> instant;
  if (cam.timestamp == CameraTimestamp::start_of_exposure) {
    instant = camera::StampInstant::kStartOfExposure;
  } else if (cam.timestamp == CameraTimestamp::end_of_frame) {
    instant = camera::StampInstant::kEndOfFrame;
  }

  std::unique_ptr<camera::CameraBackend> backend;
  if (sensor.driver == Driver::v4l2) {
    camera::V4l2CameraConfig v;
    v.path = device.path;
    v.width = cam.width;
    v.height = cam.height;
    v.format = sc.format;
    for (const auto& name : cam.v4l2_formats) {
      const auto code = camera::parse_fourcc(name);
      const auto wire = code ? camera::wire_format_from_fourcc(*code) : std::nullopt;
      if (!wire) {
        throw Error("sensor '" + sensor.name + "': livod cannot convert V4L2 format " + name +
                    " (it reads GREY, Y16, YUYV, MJPG, BGR3, RGB3)");
      }
      v.wire_formats.push_back(*wire);
    }
    v.frame_rate_hz = cam.frame_rate_hz;
    v.exposure = exposure;
    v.gain = cam.gain;
    if (cam.buffers > 0) v.buffers = cam.buffers;
    v.instant = instant;
    backend = std::make_unique<camera::V4l2Camera>(v);
  } else if (sensor.driver == Driver::aravis) {
    camera::AravisCameraConfig a;
    a.camera_id = device.camera_id;
    a.width = cam.width;
    a.height = cam.height;
    a.format = sc.format;
    a.frame_rate_hz = cam.frame_rate_hz;
    a.exposure = exposure;
    a.gain = cam.gain;
    a.trigger = cam.trigger == CameraTrigger::software   ? camera::TriggerMode::kSoftware
                : cam.trigger == CameraTrigger::hardware ? camera::TriggerMode::kHardware
                                                         : camera::TriggerMode::kFreeRun;
    a.trigger_source = cam.trigger_line;
    if (cam.buffers > 0) a.buffers = cam.buffers;
    a.packet_size = cam.packet_size;
    a.packet_resend = cam.packet_resend;
    a.chunk_exposure = cam.chunk_exposure;
    a.ptp = cam.ptp;
    if (instant) a.instant = *instant;
    // A hardware-triggered camera is silent while its trigger is: only errors mean it is gone.
    sc.reopen_on_silence = cam.trigger != CameraTrigger::hardware;
    backend = std::make_unique<camera::AravisCamera>(a);
  } else {
    throw Error("sensor '" + sensor.name + "': driver " + std::string(enum_name(sensor.driver)) +
                " is not a live camera");
  }
  return named(sensor,
               [&] { return std::make_unique<camera::CameraSource>(sc, std::move(backend)); });
}

std::unique_ptr<imu::CanImuSource> open_can_imu_source(const SensorConfig& sensor,
                                                       const LivodConfig& config,
                                                       const DeviceOpenOptions& options) {
  const DeviceSourceConfig& device = device_of(sensor);
  imu::CanImuSourceConfig c;
  c.name = sensor.name;
  c.socket.interface = device.interface;
  c.socket.fd_frames = sensor.can.fd_frames;
  // ring_capacity counts samples; a sample takes up to three frames.
  c.ring_capacity = static_cast<std::size_t>(sensor.ring_capacity) * 3;
  c.tap = options.can_tap;
  c.thread = thread_config("can:", sensor, config, options);
  c.timing.stale_after = stale_after(config);
  auto decoder = make_can_imu_decoder(sensor.can, sensor.name);
  return named(sensor, [&] { return std::make_unique<imu::CanImuSource>(c, std::move(decoder)); });
}

std::unique_ptr<imu::SerialImuSource> open_serial_imu_source(const SensorConfig& sensor,
                                                             const LivodConfig& config,
                                                             const DeviceOpenOptions& options) {
  const DeviceSourceConfig& device = device_of(sensor);
  imu::SerialImuSourceConfig c;
  c.name = sensor.name;
  c.path = device.path;
  c.baud_rate = sensor.serial.baud_rate;
  c.ring_capacity = static_cast<std::size_t>(sensor.ring_capacity);
  c.chunk_bytes = kSerialChunkBytes;
  c.tap = options.serial_tap;
  c.thread = thread_config("imu:", sensor, config, options);
  c.timing.stale_after = stale_after(config);
  auto decoder = make_serial_imu_decoder(sensor.serial, sensor.name);
  return named(sensor,
               [&] { return std::make_unique<imu::SerialImuSource>(c, std::move(decoder)); });
}

livod::ClockMode imu_clock_mode(const SensorConfig& sensor) {
  return runtime::clock_domain_config(sensor).mode;
}

}  // namespace livod::daemon::devices

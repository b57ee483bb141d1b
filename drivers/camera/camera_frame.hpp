#pragma once
// What a camera source delivers: pixels (a view into the capture ring, no copy) and the frame's
// timing, with every instant named (DESIGN.md: every measurement carries sensor, host and mapped
// time).
//
// Timing convention (docs/drivers/camera.md):
//   sensor_time     the device's stamp of `instant`, on the clock `clock` says: the host's
//                   CLOCK_MONOTONIC (V4L2 MONOTONIC buffers), the camera's own tick counter
//                   (GigE/USB3 Vision), or PTP time (a PTP-locked GigE camera).
//   host_rx         CLOCK_MONOTONIC when the host had the frame (V4L2: dequeued; Aravis: the
//                   leader packet / transfer completion, converted from CLOCK_REALTIME at once).
//   exposure        how long the shutter was open (per frame when the camera reports it).
//   exposure_start  start of exposure on the common timeline (mapped, time_offset included).
//   mid_exposure    exposure_start + exposure / 2: the instant the image shows (global shutter);
//                   the estimator uses this one.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <opencv2/core/mat.hpp>

#include "core/image.hpp"
#include "core/time.hpp"

namespace livod::camera {

// Pixel layout in the ring and of what the consumer gets.
enum class PixelFormat : std::uint8_t { kMono8, kMono16, kBgr8 };
const char* to_string(PixelFormat f);
int bytes_per_pixel(PixelFormat f);
int cv_type(PixelFormat f);

// Which instant sensor_time marks.
enum class StampInstant : std::uint8_t {
  kStartOfExposure,  // V4L2_BUF_FLAG_TSTAMP_SRC_SOE (uvcvideo), most GigE cameras' frame start
  kEndOfFrame,       // V4L2_BUF_FLAG_TSTAMP_SRC_EOF: the last pixel was received
};
const char* to_string(StampInstant i);

// Which clock sensor_time is on.
enum class CameraClockKind : std::uint8_t { kHostMonotonic, kDevice, kPtp };
const char* to_string(CameraClockKind k);

// Where the exposure value comes from.
enum class ExposureSource : std::uint8_t {
  kUnknown,     // the camera does not tell (exposure = 0)
  kFrameData,   // reported with the frame (GenICam chunk data)
  kReadback,    // the exposure control read back from the camera (may lag a frame with auto
                // exposure)
  kConfigured,  // the configured fixed exposure (the camera accepted it)
};
const char* to_string(ExposureSource s);

// Metadata written by the capture thread with the pixels.
struct FrameInfo {
  std::uint64_t sequence = 0;  // the device's frame counter (V4L2 sequence, GigE block id)
  SensorTime sensor_time;
  HostTime host_rx;
  StampInstant instant = StampInstant::kStartOfExposure;
  CameraClockKind clock = CameraClockKind::kHostMonotonic;
  Nanoseconds exposure{0};
  ExposureSource exposure_source = ExposureSource::kUnknown;
  double gain = std::nan("");        // camera units (dB for most GenICam cameras); NaN unknown
  std::int64_t trigger_host_ns = 0;  // software trigger: CLOCK_MONOTONIC when it was fired; 0 none
  HostTime ring_push;  // CLOCK_MONOTONIC when the frame entered the ring (set by the source)
  int width = 0;
  int height = 0;
  PixelFormat format = PixelFormat::kMono8;
  std::size_t stride = 0;  // bytes per row in the ring slot
};

// What the consumer's callback receives. `image` views the ring slot: valid during the callback
// only (clone it, or use to_image_frame(), to keep it).
struct CameraFrame {
  FrameInfo info;
  cv::Mat image;
  Stamp stamp;                // sensor = info.sensor_time, host = info.host_rx, mapped = the same
                              // instant on the common timeline
  MappedTime exposure_start;  // common timeline, time_offset included
  MappedTime mid_exposure;    // common timeline: the image's time for the estimator
  std::uint64_t index = 0;    // frames delivered by this source, from 0
};

// A self-contained copy for the estimator (core/image.hpp): 8-bit mono or BGR pixels (mono16 is
// scaled to 8 bits), stamped at mid-exposure.
[[nodiscard]] ImageFrame to_image_frame(const CameraFrame& frame);

}  // namespace livod::camera

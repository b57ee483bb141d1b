#include "drivers/camera/camera_frame.hpp"

#include <opencv2/core.hpp>

namespace livod::camera {

const char* to_string(PixelFormat f) {
  switch (f) {
    case PixelFormat::kMono8:
      return "mono8";
    case PixelFormat::kMono16:
      return "mono16";
    case PixelFormat::kBgr8:
      return "bgr8";
  }
  return "?";
}

int bytes_per_pixel(PixelFormat f) {
  switch (f) {
    case PixelFormat::kMono8:
      return 1;
    case PixelFormat::kMono16:
      return 2;
    case PixelFormat::kBgr8:
      return 3;
  }
  return 1;
}

int cv_type(PixelFormat f) {
  switch (f) {
    case PixelFormat::kMono8:
      return CV_8UC1;
    case PixelFormat::kMono16:
      return CV_16UC1;
    case PixelFormat::kBgr8:
      return CV_8UC3;
  }
  return CV_8UC1;
}

const char* to_string(StampInstant i) {
  return i == StampInstant::kStartOfExposure ? "start of exposure" : "end of frame";
}

const char* to_string(CameraClockKind k) {
  switch (k) {
    case CameraClockKind::kHostMonotonic:
      return "host monotonic";
    case CameraClockKind::kDevice:
      return "device";
    case CameraClockKind::kPtp:
      return "PTP";
  }
  return "?";
}

const char* to_string(ExposureSource s) {
  switch (s) {
    case ExposureSource::kUnknown:
      return "unknown";
    case ExposureSource::kFrameData:
      return "frame data";
    case ExposureSource::kReadback:
      return "control readback";
    case ExposureSource::kConfigured:
      return "configured";
  }
  return "?";
}

ImageFrame to_image_frame(const CameraFrame& frame) {
  ImageFrame out;
  out.stamp = frame.stamp;
  if (frame.info.format == PixelFormat::kMono16) {
    frame.image.convertTo(out.image, CV_8U, 1.0 / 256.0);
  } else {
    out.image = frame.image.clone();
  }
  out.exposure = frame.info.exposure;
  out.trigger_time = frame.exposure_start;
  out.mid_exposure = frame.mid_exposure;
  out.sequence = static_cast<std::uint32_t>(frame.info.sequence);
  return out;
}

}  // namespace livod::camera

#pragma once
// V4L2 cameras (UVC webcams and industrial USB cameras, MIPI sensors with a V4L2 driver) with
// mmap streaming I/O (sensor-protocols.md 6.1):
//
//   open: VIDIOC_QUERYCAP (video capture + streaming) -> VIDIOC_ENUM_FMT -> the first wire format
//         of the preference list the device offers -> VIDIOC_S_FMT at the configured size (a
//         device that answers another size is an error: the intrinsics are for that size) ->
//         VIDIOC_S_PARM frame rate -> exposure (manual, V4L2_CID_EXPOSURE_ABSOLUTE in 100 us
//         units) and gain (V4L2_CID_GAIN, driver units), read back -> VIDIOC_REQBUFS (mmap) ->
//         VIDIOC_QUERYBUF + mmap -> VIDIOC_QBUF all -> VIDIOC_STREAMON
//   each frame: poll -> VIDIOC_DQBUF -> flags, sequence, timestamp -> convert into the ring slot
//         -> VIDIOC_QBUF
//
// Timestamps: V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC buffers are CLOCK_MONOTONIC already (clock kind
// host monotonic); UNKNOWN ones are taken as CLOCK_REALTIME (old drivers) and converted at once;
// COPY (memory-to-memory devices) carries no capture time and is replaced by the dequeue time.
// V4L2_BUF_FLAG_TSTAMP_SRC_SOE marks the start of exposure (uvcvideo), EOF the end of the frame
// (then `readout` matters, see camera_clock.hpp); `instant` in the config overrides a driver that
// reports it wrong. A buffer with V4L2_BUF_FLAG_ERROR is dropped and counted; steps of the
// `sequence` field beyond one count sequence gaps.
//
// Exposure per frame: V4L2 has no per-frame exposure metadata in general; the exposure control is
// read back after every change and, while auto exposure is on, every `exposure_poll` (frames are
// tagged ExposureSource::kReadback).
//
// Loss: ENODEV (or POLLERR/POLLHUP) from poll/DQBUF means the device is gone (USB unplug); the
// source closes it and reopens the path until it is back.

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/realtime_offset.hpp"
#include "drivers/camera/camera_backend.hpp"
#include "drivers/camera/pixel_convert.hpp"
#include "drivers/camera/v4l2_device.hpp"

namespace livod::camera {

struct V4l2CameraConfig {
  std::string path;  // /dev/video0 or a stable /dev/v4l/by-id/... link
  int width = 0;
  int height = 0;
  PixelFormat format = PixelFormat::kMono8;
  // Wire formats to ask for, best first; empty = preferred_wire_formats(format).
  std::vector<WireFormat> wire_formats;
  std::optional<double> frame_rate_hz;
  std::optional<Nanoseconds> exposure;  // fixed exposure (auto exposure off); unset = leave it
  std::optional<double> gain;           // V4L2_CID_GAIN in driver units; unset = leave it
  int buffers = 4;
  std::optional<StampInstant> instant;  // overrides the driver's TSTAMP_SRC flag
  Nanoseconds exposure_poll{std::chrono::seconds(1)};
};

class V4l2Camera final : public CameraBackend {
 public:
  // `device` = nullptr: the real kernel interface.
  explicit V4l2Camera(V4l2CameraConfig config, std::shared_ptr<V4l2Device> device = nullptr);
  ~V4l2Camera() override;

  void open() override;
  void close() noexcept override;
  Result next_frame(std::chrono::milliseconds timeout, FrameSink& sink) override;
  bool service() override;
  [[nodiscard]] std::string describe() const override { return "V4L2 " + config_.path; }
  [[nodiscard]] std::string loss_reason() const override { return loss_reason_; }

  // After open (capture thread or after stop): what was negotiated.
  [[nodiscard]] std::optional<WireFormat> wire_format() const { return wire_; }

 private:
  struct Buffer {
    void* data = nullptr;
    std::size_t length = 0;
  };

  [[noreturn]] void fail(const std::string& what, int err) const;
  void negotiate_format();
  void apply_controls(const CameraControls& c, bool at_open);
  void read_back_exposure();
  int get_control(std::uint32_t id, std::int32_t& value);
  int set_control(std::uint32_t id, std::int32_t value);

  V4l2CameraConfig config_;
  std::shared_ptr<V4l2Device> dev_;
  int fd_ = -1;
  std::vector<Buffer> buffers_;
  bool streaming_ = false;
  std::optional<WireFormat> wire_;
  std::size_t stride_ = 0;
  std::size_t size_image_ = 0;
  bool have_sequence_ = false;
  std::uint32_t last_sequence_ = 0;
  bool auto_exposure_ = true;
  bool exposure_known_ = false;
  Nanoseconds exposure_{0};
  ExposureSource exposure_source_ = ExposureSource::kUnknown;
  double gain_ = std::nan("");
  std::int64_t next_exposure_poll_ns_ = 0;
  RealtimeToMonotonic realtime_;
  std::int64_t next_realtime_refresh_ns_ = 0;
  std::string loss_reason_;
};

}  // namespace livod::camera

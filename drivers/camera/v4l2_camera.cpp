#include "drivers/camera/v4l2_camera.hpp"

#include <linux/videodev2.h>

#include <cerrno>
#include <cstring>

#include "core/error.hpp"
#include "core/realtime_offset.hpp"

namespace livod::camera {
namespace {

constexpr std::int64_t kExposureUnitNs = 100'000;  // V4L2_CID_EXPOSURE_ABSOLUTE: 100 us

std::string err_text(int err) {
  return std::strerror(err < 0 ? -err : err);
}

}  // namespace

V4l2Camera::V4l2Camera(V4l2CameraConfig config, std::shared_ptr<V4l2Device> device)
    : config_(std::move(config)),
      dev_(device ? std::move(device) : std::make_shared<SystemV4l2Device>()) {
  if (config_.wire_formats.empty()) config_.wire_formats = preferred_wire_formats(config_.format);
  if (config_.buffers < 2) config_.buffers = 2;
}

V4l2Camera::~V4l2Camera() {
  close();
}

void V4l2Camera::fail(const std::string& what, int err) const {
  throw Error("V4L2 device " + config_.path + ": " + what +
              (err != 0 ? " (" + err_text(err) + ")" : std::string()));
}

int V4l2Camera::get_control(std::uint32_t id, std::int32_t& value) {
  v4l2_control c{};
  c.id = id;
  const int rc = dev_->ioctl(fd_, VIDIOC_G_CTRL, &c);
  if (rc == 0) value = c.value;
  return rc;
}

int V4l2Camera::set_control(std::uint32_t id, std::int32_t value) {
  v4l2_control c{};
  c.id = id;
  c.value = value;
  return dev_->ioctl(fd_, VIDIOC_S_CTRL, &c);
}

void V4l2Camera::open() {
  loss_reason_.clear();
  const int fd = dev_->open(config_.path);
  if (fd < 0) {
    fail(fd == -ENOENT ? "does not exist" : "cannot be opened", fd == -ENOENT ? 0 : fd);
  }
  fd_ = fd;
  try {
    v4l2_capability cap{};
    if (const int rc = dev_->ioctl(fd_, VIDIOC_QUERYCAP, &cap); rc < 0) {
      fail("is not a V4L2 device (VIDIOC_QUERYCAP)", rc);
    }
    const std::uint32_t caps =
        (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
    if ((caps & V4L2_CAP_VIDEO_CAPTURE) == 0) fail("is not a video capture device", 0);
    if ((caps & V4L2_CAP_STREAMING) == 0) fail("does not support streaming I/O", 0);
    negotiate_format();

    if (config_.frame_rate_hz) {
      v4l2_streamparm parm{};
      parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      if (dev_->ioctl(fd_, VIDIOC_G_PARM, &parm) < 0 ||
          (parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME) == 0) {
        fail("cannot set the frame rate (no V4L2_CAP_TIMEPERFRAME); leave frame_rate_hz unset", 0);
      }
      parm.parm.capture.timeperframe.numerator = 1000;
      parm.parm.capture.timeperframe.denominator =
          static_cast<std::uint32_t>(*config_.frame_rate_hz * 1000.0 + 0.5);
      if (const int rc = dev_->ioctl(fd_, VIDIOC_S_PARM, &parm); rc < 0) {
        fail("VIDIOC_S_PARM (frame rate) failed", rc);
      }
    }
    apply_controls({config_.exposure, config_.gain}, true);
    read_back_exposure();

    v4l2_requestbuffers req{};
    req.count = static_cast<std::uint32_t>(config_.buffers);
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    if (const int rc = dev_->ioctl(fd_, VIDIOC_REQBUFS, &req); rc < 0 || req.count < 2) {
      fail("VIDIOC_REQBUFS (mmap buffers) failed", rc);
    }
    buffers_.resize(req.count);
    for (std::uint32_t i = 0; i < req.count; ++i) {
      v4l2_buffer b{};
      b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      b.memory = V4L2_MEMORY_MMAP;
      b.index = i;
      if (const int rc = dev_->ioctl(fd_, VIDIOC_QUERYBUF, &b); rc < 0)
        fail("VIDIOC_QUERYBUF failed", rc);
      void* p = dev_->mmap(b.length, fd_, static_cast<off_t>(b.m.offset));
      if (p == nullptr) fail("mmap of a capture buffer failed", 0);
      buffers_[i] = {p, b.length};
      if (const int rc = dev_->ioctl(fd_, VIDIOC_QBUF, &b); rc < 0) fail("VIDIOC_QBUF failed", rc);
    }
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (const int rc = dev_->ioctl(fd_, VIDIOC_STREAMON, &type); rc < 0)
      fail("VIDIOC_STREAMON failed", rc);
    streaming_ = true;
  } catch (...) {
    close();
    throw;
  }
  have_sequence_ = false;
  realtime_.refresh();
}

void V4l2Camera::negotiate_format() {
  std::vector<std::uint32_t> offered;
  for (std::uint32_t i = 0; i < 256; ++i) {
    v4l2_fmtdesc d{};
    d.index = i;
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (dev_->ioctl(fd_, VIDIOC_ENUM_FMT, &d) < 0) break;
    offered.push_back(d.pixelformat);
  }
  std::optional<WireFormat> chosen;
  for (const WireFormat w : config_.wire_formats) {
    if (can_convert(w, config_.format) &&
        std::find(offered.begin(), offered.end(), fourcc(w)) != offered.end()) {
      chosen = w;
      break;
    }
  }
  if (!chosen) {
    std::string have;
    for (const auto c : offered) have += (have.empty() ? "" : ", ") + fourcc_name(c);
    std::string want;
    for (const auto w : config_.wire_formats) {
      if (can_convert(w, config_.format))
        want += (want.empty() ? "" : ", ") + fourcc_name(fourcc(w));
    }
    fail("offers none of the formats livod can convert to " +
             std::string(to_string(config_.format)) + " (wanted: " + want +
             "; the device offers: " + (have.empty() ? "none" : have) + ")",
         0);
  }
  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = static_cast<std::uint32_t>(config_.width);
  fmt.fmt.pix.height = static_cast<std::uint32_t>(config_.height);
  fmt.fmt.pix.pixelformat = fourcc(*chosen);
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  if (const int rc = dev_->ioctl(fd_, VIDIOC_S_FMT, &fmt); rc < 0) fail("VIDIOC_S_FMT failed", rc);
  if (fmt.fmt.pix.pixelformat != fourcc(*chosen)) {
    fail("refused format " + fourcc_name(fourcc(*chosen)) + " (answered " +
             fourcc_name(fmt.fmt.pix.pixelformat) + ")",
         0);
  }
  if (static_cast<int>(fmt.fmt.pix.width) != config_.width ||
      static_cast<int>(fmt.fmt.pix.height) != config_.height) {
    fail("delivers " + std::to_string(fmt.fmt.pix.width) + "x" +
             std::to_string(fmt.fmt.pix.height) + " in " + fourcc_name(fmt.fmt.pix.pixelformat) +
             ", not the configured " + std::to_string(config_.width) + "x" +
             std::to_string(config_.height) + " (the intrinsics are for the configured size)",
         0);
  }
  wire_ = chosen;
  stride_ = fmt.fmt.pix.bytesperline;
  size_image_ = fmt.fmt.pix.sizeimage;
}

void V4l2Camera::apply_controls(const CameraControls& c, bool at_open) {
  if (c.exposure) {
    int rc = set_control(V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL);
    const auto units = static_cast<std::int32_t>(
        std::max<std::int64_t>(1, (c.exposure->count() + kExposureUnitNs / 2) / kExposureUnitNs));
    if (rc == 0) rc = set_control(V4L2_CID_EXPOSURE_ABSOLUTE, units);
    if (rc < 0) {
      if (at_open) fail("cannot set a manual exposure (V4L2_CID_EXPOSURE_ABSOLUTE)", rc);
      stats_.add_control_error();
    } else {
      auto_exposure_ = false;
    }
  }
  if (c.gain) {
    const int rc = set_control(V4L2_CID_GAIN, static_cast<std::int32_t>(std::lround(*c.gain)));
    if (rc < 0) {
      if (at_open) fail("cannot set the gain (V4L2_CID_GAIN)", rc);
      stats_.add_control_error();
    }
  }
  if (c.exposure || c.gain) read_back_exposure();
}

void V4l2Camera::read_back_exposure() {
  std::int32_t mode = 0;
  if (get_control(V4L2_CID_EXPOSURE_AUTO, mode) == 0) auto_exposure_ = mode != V4L2_EXPOSURE_MANUAL;
  std::int32_t units = 0;
  if (get_control(V4L2_CID_EXPOSURE_ABSOLUTE, units) == 0 && units > 0) {
    exposure_ = Nanoseconds(std::int64_t{units} * kExposureUnitNs);
    exposure_known_ = true;
    exposure_source_ = ExposureSource::kReadback;
    stats_.set_exposure(exposure_);
  } else {
    exposure_known_ = false;
    exposure_source_ = ExposureSource::kUnknown;
  }
  std::int32_t g = 0;
  if (get_control(V4L2_CID_GAIN, g) == 0) {
    gain_ = g;
    stats_.set_gain(gain_);
  }
  next_exposure_poll_ns_ = host_now().ns + config_.exposure_poll.count();
}

void V4l2Camera::close() noexcept {
  if (fd_ < 0) return;
  if (streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    dev_->ioctl(fd_, VIDIOC_STREAMOFF, &type);
    streaming_ = false;
  }
  for (const auto& b : buffers_) {
    if (b.data != nullptr) dev_->munmap(b.data, b.length);
  }
  buffers_.clear();
  v4l2_requestbuffers req{};
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  dev_->ioctl(fd_, VIDIOC_REQBUFS, &req);  // count 0 frees them (fails harmlessly when gone)
  dev_->close(fd_);
  fd_ = -1;
}

bool V4l2Camera::service() {
  if (auto c = mailbox_.take()) apply_controls(*c, false);
  const std::int64_t now = host_now().ns;
  if (auto_exposure_ && now >= next_exposure_poll_ns_) read_back_exposure();
  if (now >= next_realtime_refresh_ns_) {
    realtime_.refresh();
    next_realtime_refresh_ns_ = now + kRealtimeOffsetRefreshNs;
  }
  return true;
}

CameraBackend::Result V4l2Camera::next_frame(std::chrono::milliseconds timeout, FrameSink& sink) {
  const int ready = dev_->poll(fd_, static_cast<int>(timeout.count()));
  if (ready == 0) return Result::kIdle;
  if (ready < 0) {
    loss_reason_ = describe() + ": " + err_text(ready);
    return Result::kLost;
  }
  v4l2_buffer b{};
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  const int rc = dev_->ioctl(fd_, VIDIOC_DQBUF, &b);
  if (rc == -EAGAIN) return Result::kIdle;
  if (rc < 0) {
    loss_reason_ = describe() + ": VIDIOC_DQBUF: " + err_text(rc);
    return Result::kLost;
  }
  const HostTime rx = host_now();
  stats_.add_frame(b.bytesused, rx.ns);
  if (have_sequence_) {
    const std::uint32_t step = b.sequence - last_sequence_;
    if (step > 1 && step < 0x80000000U) stats_.add_gaps(step - 1);
  }
  have_sequence_ = true;
  last_sequence_ = b.sequence;

  Result result = Result::kFrame;
  if ((b.flags & V4L2_BUF_FLAG_ERROR) != 0 || b.index >= buffers_.size()) {
    stats_.add_incomplete();
    result = Result::kDropped;
  } else if (cv::Mat slot = sink.acquire(config_.width, config_.height); !slot.empty()) {
    const WireImage wire{{static_cast<const std::byte*>(buffers_[b.index].data),
                          std::min<std::size_t>(b.bytesused, buffers_[b.index].length)},
                         config_.width,
                         config_.height,
                         stride_,
                         *wire_};
    const ConvertStatus status = convert_image(wire, slot);
    if (status != ConvertStatus::kOk) {
      stats_.add_convert_error();
      result = Result::kDropped;
    } else {
      FrameInfo info;
      info.sequence = b.sequence;
      info.host_rx = rx;
      const std::int64_t stamp_ns = std::int64_t{b.timestamp.tv_sec} * 1'000'000'000 +
                                    std::int64_t{b.timestamp.tv_usec} * 1000;
      switch (b.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) {
        case V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC:
          info.sensor_time = SensorTime(stamp_ns);
          break;
        case V4L2_BUF_FLAG_TIMESTAMP_COPY:
          info.sensor_time = SensorTime(rx.ns);  // no capture time: the dequeue time
          break;
        default:  // UNKNOWN: legacy drivers stamp with the wall clock
          info.sensor_time = SensorTime(realtime_.to_host(stamp_ns).ns);
          break;
      }
      info.clock = CameraClockKind::kHostMonotonic;
      const bool copy = (b.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_COPY;
      info.instant =
          config_.instant ? *config_.instant
          : (!copy && (b.flags & V4L2_BUF_FLAG_TSTAMP_SRC_MASK) == V4L2_BUF_FLAG_TSTAMP_SRC_SOE)
              ? StampInstant::kStartOfExposure
              : StampInstant::kEndOfFrame;
      info.exposure = exposure_known_ ? exposure_ : Nanoseconds(0);
      info.exposure_source = exposure_source_;
      info.gain = gain_;
      info.width = config_.width;
      info.height = config_.height;
      info.format = config_.format;
      info.stride = slot.step[0];
      sink.commit(info);
    }
  }
  if (const int q = dev_->ioctl(fd_, VIDIOC_QBUF, &b); q < 0) {
    loss_reason_ = describe() + ": VIDIOC_QBUF: " + err_text(q);
    return Result::kLost;
  }
  return result;
}

}  // namespace livod::camera

#include "drivers/camera/v4l2_recorded.hpp"

#include <linux/videodev2.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <thread>

namespace livod::camera {
namespace {

constexpr int kFirstFd = 1000;
constexpr std::uint32_t kOffsetStride = 1U << 24;  // mmap offsets: slot index * stride

std::size_t wire_bytes_per_pixel(std::uint32_t fourcc) {
  switch (fourcc) {
    case V4L2_PIX_FMT_GREY:
      return 1;
    case V4L2_PIX_FMT_Y16:
    case V4L2_PIX_FMT_YUYV:
      return 2;
    case V4L2_PIX_FMT_BGR24:
    case V4L2_PIX_FMT_RGB24:
      return 3;
    default:
      return 0;  // compressed
  }
}

}  // namespace

RecordedV4l2Device::RecordedV4l2Device(V4l2Recording recording) : rec_(std::move(recording)) {
  pending_.assign(rec_.frames.begin(), rec_.frames.end());
  controls_[V4L2_CID_EXPOSURE_AUTO] =
      rec_.auto_exposure ? V4L2_EXPOSURE_AUTO : V4L2_EXPOSURE_MANUAL;
  controls_[V4L2_CID_EXPOSURE_ABSOLUTE] = rec_.exposure_100us;
  controls_[V4L2_CID_GAIN] = 0;
}

int RecordedV4l2Device::open(const std::string& path) {
  const std::lock_guard lock(mutex_);
  if (path != rec_.path || !plugged_) return -ENOENT;
  if (open_fd_ >= 0) return -EBUSY;
  open_fd_ = kFirstFd + (++generation_);
  ++opens_;
  return open_fd_;
}

void RecordedV4l2Device::close(int fd) {
  const std::lock_guard lock(mutex_);
  if (fd == open_fd_) {
    open_fd_ = -1;
    streaming_ = false;
    slots_.clear();
  }
}

int RecordedV4l2Device::ioctl(int fd, unsigned long request, void* arg) {
  const std::lock_guard lock(mutex_);
  if (fd != open_fd_) return -EBADF;
  if (!plugged_) return -ENODEV;
  switch (request) {
    case VIDIOC_QUERYCAP: {
      auto* cap = static_cast<v4l2_capability*>(arg);
      *cap = {};
      std::strncpy(reinterpret_cast<char*>(cap->driver), "livod-recorded", sizeof(cap->driver) - 1);
      std::strncpy(reinterpret_cast<char*>(cap->card), rec_.card.c_str(), sizeof(cap->card) - 1);
      cap->device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
      cap->capabilities = cap->device_caps | V4L2_CAP_DEVICE_CAPS;
      return 0;
    }
    case VIDIOC_ENUM_FMT: {
      auto* d = static_cast<v4l2_fmtdesc*>(arg);
      if (d->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || d->index >= rec_.formats.size()) return -EINVAL;
      d->pixelformat = rec_.formats[d->index];
      return 0;
    }
    case VIDIOC_S_FMT: {
      auto* f = static_cast<v4l2_format*>(arg);
      if (streaming_) return -EBUSY;
      const auto it = std::find(rec_.formats.begin(), rec_.formats.end(), f->fmt.pix.pixelformat);
      if (it == rec_.formats.end()) f->fmt.pix.pixelformat = rec_.formats.at(0);  // as drivers do
      fourcc_ = f->fmt.pix.pixelformat;
      f->fmt.pix.width = static_cast<std::uint32_t>(rec_.width);
      f->fmt.pix.height = static_cast<std::uint32_t>(rec_.height);
      const std::size_t bpp = wire_bytes_per_pixel(fourcc_);
      f->fmt.pix.bytesperline =
          static_cast<std::uint32_t>(bpp * static_cast<std::size_t>(rec_.width));
      size_image_ = bpp > 0 ? f->fmt.pix.bytesperline * static_cast<std::size_t>(rec_.height)
                            : static_cast<std::size_t>(rec_.width) * rec_.height * 2;
      for (const auto& fr : pending_) size_image_ = std::max(size_image_, fr.bytes.size());
      f->fmt.pix.sizeimage = static_cast<std::uint32_t>(size_image_);
      return 0;
    }
    case VIDIOC_G_PARM:
    case VIDIOC_S_PARM: {
      auto* p = static_cast<v4l2_streamparm*>(arg);
      if (!rec_.timeperframe) return request == VIDIOC_G_PARM ? 0 : -EINVAL;
      p->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
      if (request == VIDIOC_S_PARM && p->parm.capture.timeperframe.numerator > 0) {
        frame_rate_ = static_cast<double>(p->parm.capture.timeperframe.denominator) /
                      p->parm.capture.timeperframe.numerator;
      }
      return 0;
    }
    case VIDIOC_G_CTRL:
    case VIDIOC_S_CTRL: {
      auto* c = static_cast<v4l2_control*>(arg);
      if (!rec_.exposure_controls || !controls_.contains(c->id)) return -EINVAL;
      if (request == VIDIOC_G_CTRL) {
        c->value = controls_[c->id];
      } else {
        controls_[c->id] = c->value;
      }
      return 0;
    }
    case VIDIOC_REQBUFS: {
      auto* r = static_cast<v4l2_requestbuffers*>(arg);
      if (r->memory != V4L2_MEMORY_MMAP) return -EINVAL;
      slots_.clear();
      slots_.resize(r->count);
      for (auto& s : slots_) s.memory.assign(size_image_, 0);
      return 0;
    }
    case VIDIOC_QUERYBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (b->index >= slots_.size()) return -EINVAL;
      b->length = static_cast<std::uint32_t>(slots_[b->index].memory.size());
      b->m.offset = b->index * kOffsetStride;
      return 0;
    }
    case VIDIOC_QBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (b->index >= slots_.size() || slots_[b->index].queued) return -EINVAL;
      slots_[b->index].queued = true;
      return 0;
    }
    case VIDIOC_STREAMON:
      streaming_ = true;
      return 0;
    case VIDIOC_STREAMOFF:
      streaming_ = false;
      for (auto& s : slots_) s.queued = false;
      return 0;
    case VIDIOC_DQBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (!streaming_) return -EINVAL;
      auto slot =
          std::find_if(slots_.begin(), slots_.end(), [](const Slot& s) { return s.queued; });
      if (pending_.empty() || slot == slots_.end()) return -EAGAIN;
      const RecordedBuffer f = pending_.front();
      pending_.pop_front();
      slot->queued = false;
      const std::size_t n = std::min(f.bytes.size(), slot->memory.size());
      std::memcpy(slot->memory.data(), f.bytes.data(), n);
      const auto index = static_cast<std::uint32_t>(slot - slots_.begin());
      *b = {};
      b->type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      b->memory = V4L2_MEMORY_MMAP;
      b->index = index;
      b->bytesused = static_cast<std::uint32_t>(n);
      b->sequence = f.sequence;
      b->flags = f.flags;
      b->timestamp.tv_sec = f.timestamp_ns / 1'000'000'000;
      b->timestamp.tv_usec = (f.timestamp_ns % 1'000'000'000) / 1000;
      b->length = static_cast<std::uint32_t>(slot->memory.size());
      ++delivered_;
      last_dequeue_ = std::chrono::steady_clock::now();
      return 0;
    }
    default:
      return -ENOTTY;
  }
}

void* RecordedV4l2Device::mmap(std::size_t length, int fd, off_t offset) {
  const std::lock_guard lock(mutex_);
  if (fd != open_fd_) return nullptr;
  const auto index = static_cast<std::size_t>(offset) / kOffsetStride;
  if (index >= slots_.size() || length > slots_[index].memory.size()) return nullptr;
  return slots_[index].memory.data();
}

void RecordedV4l2Device::munmap(void* /*address*/, std::size_t /*length*/) {}

int RecordedV4l2Device::poll(int fd, int timeout_ms) {
  auto wait = std::chrono::nanoseconds(std::chrono::milliseconds(timeout_ms));
  {
    const std::lock_guard lock(mutex_);
    if (fd != open_fd_ || !plugged_) return -ENODEV;
    const bool queued =
        std::any_of(slots_.begin(), slots_.end(), [](const Slot& s) { return s.queued; });
    if (streaming_ && queued && !pending_.empty()) {
      const auto due = last_dequeue_ + rec_.pace;
      const auto now = std::chrono::steady_clock::now();
      if (now >= due) return 1;
      if (due - now < wait) {
        std::this_thread::sleep_for(due - now);
        return 1;
      }
    }
  }
  std::this_thread::sleep_for(wait);
  return 0;
}

void RecordedV4l2Device::unplug() {
  const std::lock_guard lock(mutex_);
  plugged_ = false;
}

void RecordedV4l2Device::plug() {
  const std::lock_guard lock(mutex_);
  plugged_ = true;
}

void RecordedV4l2Device::add_frames(const std::vector<RecordedBuffer>& frames) {
  const std::lock_guard lock(mutex_);
  pending_.insert(pending_.end(), frames.begin(), frames.end());
}

std::size_t RecordedV4l2Device::delivered() const {
  const std::lock_guard lock(mutex_);
  return delivered_;
}

std::uint32_t RecordedV4l2Device::negotiated_fourcc() const {
  const std::lock_guard lock(mutex_);
  return fourcc_;
}

std::optional<double> RecordedV4l2Device::frame_rate() const {
  const std::lock_guard lock(mutex_);
  return frame_rate_;
}

std::int32_t RecordedV4l2Device::exposure_100us() const {
  const std::lock_guard lock(mutex_);
  return controls_.at(V4L2_CID_EXPOSURE_ABSOLUTE);
}

bool RecordedV4l2Device::auto_exposure() const {
  const std::lock_guard lock(mutex_);
  return controls_.at(V4L2_CID_EXPOSURE_AUTO) != V4L2_EXPOSURE_MANUAL;
}

int RecordedV4l2Device::opens() const {
  const std::lock_guard lock(mutex_);
  return opens_;
}

}  // namespace livod::camera

#pragma once
// A V4L2 device that answers the backend's calls from recorded buffers: the formats a device
// offers, its controls, and a sequence of dequeued buffers (bytes, sequence number, timestamp,
// flags) exactly as VIDIOC_DQBUF returns them. The real V4l2Camera backend runs on it unchanged,
// so format conversion, timestamp/flag handling, sequence gaps, exposure control and device loss
// are tested without a camera. It can also "unplug" the device (open fails with ENOENT, a
// streaming descriptor gets ENODEV) and plug it back.
//
// Thread-safe: the capture thread makes the V4L2 calls while a test thread unplugs, plugs and
// reads what was set.

#include <chrono>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "drivers/camera/v4l2_device.hpp"

namespace livod::camera {

struct RecordedBuffer {
  std::vector<std::uint8_t> bytes;  // bytesused
  std::uint32_t sequence = 0;
  std::int64_t timestamp_ns = 0;  // struct timeval: truncated to microseconds on the way
  std::uint32_t flags = 0;        // V4L2_BUF_FLAG_* (TIMESTAMP_MASK, TSTAMP_SRC_MASK, ERROR)
};

struct V4l2Recording {
  std::string path = "/dev/video0";
  std::string card = "recorded camera";
  std::vector<std::uint32_t> formats;  // fourcc codes VIDIOC_ENUM_FMT lists, in order
  int width = 0;                       // the size the device delivers (S_FMT answers this)
  int height = 0;
  bool timeperframe = true;           // V4L2_CAP_TIMEPERFRAME
  bool exposure_controls = true;      // EXPOSURE_AUTO / EXPOSURE_ABSOLUTE / GAIN exist
  std::int32_t exposure_100us = 100;  // initial EXPOSURE_ABSOLUTE
  bool auto_exposure = true;
  // Minimum time between two dequeued buffers (a camera's frame period); 0 = as fast as asked.
  std::chrono::nanoseconds pace{0};
  std::vector<RecordedBuffer> frames;
};

class RecordedV4l2Device final : public V4l2Device {
 public:
  explicit RecordedV4l2Device(V4l2Recording recording);

  int open(const std::string& path) override;
  void close(int fd) override;
  int ioctl(int fd, unsigned long request, void* arg) override;
  void* mmap(std::size_t length, int fd, off_t offset) override;
  void munmap(void* address, std::size_t length) override;
  int poll(int fd, int timeout_ms) override;

  // The device disappears (open: ENOENT; the open descriptor: ENODEV) / comes back.
  void unplug();
  void plug();
  // Appends frames to deliver (e.g. after a replug).
  void add_frames(const std::vector<RecordedBuffer>& frames);

  [[nodiscard]] std::size_t delivered() const;
  [[nodiscard]] std::uint32_t negotiated_fourcc() const;
  [[nodiscard]] std::optional<double> frame_rate() const;
  [[nodiscard]] std::int32_t exposure_100us() const;
  [[nodiscard]] bool auto_exposure() const;
  [[nodiscard]] int opens() const;

 private:
  struct Slot {
    std::vector<std::uint8_t> memory;
    bool queued = false;
  };

  mutable std::mutex mutex_;
  V4l2Recording rec_;
  std::deque<RecordedBuffer> pending_;
  std::vector<Slot> slots_;
  std::size_t size_image_ = 0;
  std::uint32_t fourcc_ = 0;
  std::optional<double> frame_rate_;
  std::map<std::uint32_t, std::int32_t> controls_;
  bool plugged_ = true;
  bool streaming_ = false;
  int open_fd_ = -1;
  int generation_ = 0;  // descriptors of an unplugged device stay dead
  std::size_t delivered_ = 0;
  std::chrono::steady_clock::time_point last_dequeue_{};
  int opens_ = 0;
};

}  // namespace livod::camera

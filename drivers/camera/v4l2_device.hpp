#pragma once
// The system calls the V4L2 backend makes, behind an interface: SystemV4l2Device calls the kernel
// (open, ioctl, mmap, poll on /dev/videoN); RecordedV4l2Device (v4l2_recorded.hpp) answers them
// from recorded buffers, so that the whole backend (format negotiation, buffer handling, flags,
// sequence gaps, device loss) runs in tests on a machine without a camera.
//
// Return convention: >= 0 success, -errno on failure (no errno side channel).

#include <sys/types.h>
#include <cstddef>
#include <string>

namespace livod::camera {

class V4l2Device {
 public:
  virtual ~V4l2Device() = default;
  // Returns a descriptor or -errno.
  virtual int open(const std::string& path) = 0;
  virtual void close(int fd) = 0;
  // 0 or -errno (EINTR is retried by the implementation).
  virtual int ioctl(int fd, unsigned long request, void* arg) = 0;
  // nullptr on failure.
  virtual void* mmap(std::size_t length, int fd, off_t offset) = 0;
  virtual void munmap(void* address, std::size_t length) = 0;
  // Waits for a dequeuable buffer: 1 ready, 0 timeout, -errno (or -ENODEV on POLLERR/POLLHUP).
  virtual int poll(int fd, int timeout_ms) = 0;
};

class SystemV4l2Device final : public V4l2Device {
 public:
  int open(const std::string& path) override;
  void close(int fd) override;
  int ioctl(int fd, unsigned long request, void* arg) override;
  void* mmap(std::size_t length, int fd, off_t offset) override;
  void munmap(void* address, std::size_t length) override;
  int poll(int fd, int timeout_ms) override;
};

}  // namespace livod::camera

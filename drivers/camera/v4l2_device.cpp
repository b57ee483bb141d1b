#include "drivers/camera/v4l2_device.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>

namespace livod::camera {

int SystemV4l2Device::open(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  return fd >= 0 ? fd : -errno;
}

void SystemV4l2Device::close(int fd) {
  ::close(fd);
}

int SystemV4l2Device::ioctl(int fd, unsigned long request, void* arg) {
  int rc = 0;
  do {
    rc = ::ioctl(fd, request, arg);
  } while (rc < 0 && errno == EINTR);
  return rc < 0 ? -errno : 0;
}

void* SystemV4l2Device::mmap(std::size_t length, int fd, off_t offset) {
  void* p = ::mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, offset);
  return p == MAP_FAILED ? nullptr : p;
}

void SystemV4l2Device::munmap(void* address, std::size_t length) {
  ::munmap(address, length);
}

int SystemV4l2Device::poll(int fd, int timeout_ms) {
  pollfd pfd{fd, POLLIN, 0};
  const int rc = ::poll(&pfd, 1, timeout_ms);
  if (rc < 0) return errno == EINTR ? 0 : -errno;
  if (rc == 0) return 0;
  if ((pfd.revents & POLLIN) != 0) return 1;
  return -ENODEV;  // POLLERR / POLLHUP: the device went away (unplugged USB camera)
}

}  // namespace livod::camera

#include "daemon/runtime/cpu_latency_request.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <utility>

#include <fmt/format.h>

namespace livod::daemon::runtime {

CpuLatencyRequest::CpuLatencyRequest(int max_latency_us, const std::filesystem::path& device) {
  const int fd = ::open(device.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) {
    refusal_ = fmt::format("realtime.cpu_dma_latency_us: cannot open {}: {}", device.string(),
                           std::strerror(errno));
    return;
  }
  // The kernel takes a binary s32 (a hex string is accepted too; binary is the documented form).
  const std::int32_t value = max_latency_us;
  const ssize_t written = ::write(fd, &value, sizeof value);
  if (written != static_cast<ssize_t>(sizeof value)) {
    refusal_ = fmt::format("realtime.cpu_dma_latency_us: writing {} to {}: {}", max_latency_us,
                           device.string(), written < 0 ? std::strerror(errno) : "short write");
    ::close(fd);
    return;
  }
  fd_ = fd;
}

CpuLatencyRequest::~CpuLatencyRequest() {
  release();
}

CpuLatencyRequest::CpuLatencyRequest(CpuLatencyRequest&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), refusal_(std::move(other.refusal_)) {}

CpuLatencyRequest& CpuLatencyRequest::operator=(CpuLatencyRequest&& other) noexcept {
  if (this != &other) {
    release();
    fd_ = std::exchange(other.fd_, -1);
    refusal_ = std::move(other.refusal_);
  }
  return *this;
}

void CpuLatencyRequest::release() noexcept {
  if (fd_ >= 0) ::close(fd_);  // closing the file ends the request
  fd_ = -1;
}

}  // namespace livod::daemon::runtime

#include "tests/runtime/fake_service_manager.hpp"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstring>
#include <stdexcept>

namespace livod::test {

FakeServiceManager::FakeServiceManager() {
  fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error(std::string("socket(AF_UNIX): ") + std::strerror(errno));
  static std::atomic<int> instances{0};
  const std::string name = "livod-notify-test-" + std::to_string(::getpid()) + "-" +
                           std::to_string(instances.fetch_add(1));
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  // Abstract namespace: sun_path[0] = 0, spelled "@name" in NOTIFY_SOCKET.
  name.copy(addr.sun_path + 1, sizeof(addr.sun_path) - 2);
  const auto len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + 1 + name.size());
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), len) != 0) {
    const std::string error = std::strerror(errno);
    ::close(fd_);
    throw std::runtime_error("bind @" + name + ": " + error);
  }
  timeval tv{0, 50'000};  // the reader checks for its stop this often
  ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
  address_ = "@" + name;
  reader_ = std::jthread([this](const std::stop_token& stop) {
    char buf[4096];
    while (!stop.stop_requested()) {
      const ssize_t n = ::recv(fd_, buf, sizeof(buf), 0);
      if (n <= 0) continue;
      const std::lock_guard lock(mutex_);
      messages_.push_back({Clock::now(), std::string(buf, static_cast<std::size_t>(n))});
    }
  });
}

FakeServiceManager::~FakeServiceManager() {
  reader_.request_stop();
  reader_.join();
  ::close(fd_);
}

std::vector<FakeServiceManager::Message> FakeServiceManager::messages() {
  const std::lock_guard lock(mutex_);
  return messages_;
}

bool FakeServiceManager::wait_for(const std::string& prefix, std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  while (Clock::now() < deadline) {
    for (const auto& m : messages()) {
      if (m.text.rfind(prefix, 0) == 0) return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

}  // namespace livod::test

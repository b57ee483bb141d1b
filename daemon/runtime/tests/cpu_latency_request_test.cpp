// CpuLatencyRequest: the PM QoS request is written as the kernel reads it, held while the object
// lives and released with it; a refusal is a message, not an exception.

#include "daemon/runtime/cpu_latency_request.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace livod::daemon::runtime {
namespace {

namespace fs = std::filesystem;

// How many of this process's open files are `path`.
int open_count(const fs::path& path) {
  int n = 0;
  for (const auto& fd : fs::directory_iterator("/proc/self/fd")) {
    std::error_code ec;
    if (fs::read_symlink(fd.path(), ec) == fs::canonical(path)) ++n;
  }
  return n;
}

std::vector<char> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

fs::path scratch_file(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / (name + "-" + std::to_string(::getpid()));
  std::ofstream(p).close();
  return p;
}

TEST(CpuLatencyRequest, WritesTheBoundAsABinaryS32AndHoldsTheFileOpenUntilReleased) {
  const fs::path device = scratch_file("livod-cpu-latency");
  {
    CpuLatencyRequest request(25, device);
    ASSERT_TRUE(request.active()) << request.refusal();
    EXPECT_TRUE(request.refusal().empty());
    const auto bytes = read_bytes(device);
    ASSERT_EQ(bytes.size(), sizeof(std::int32_t));
    std::int32_t value = -1;
    std::memcpy(&value, bytes.data(), sizeof value);
    EXPECT_EQ(value, 25);
    EXPECT_EQ(open_count(device), 1);  // the request lasts as long as the file is open

    CpuLatencyRequest moved = std::move(request);
    EXPECT_TRUE(moved.active());
    EXPECT_FALSE(request.active());  // NOLINT(bugprone-use-after-move): moved-from is defined
    EXPECT_EQ(open_count(device), 1);
  }
  EXPECT_EQ(open_count(device), 0);
  fs::remove(device);
}

TEST(CpuLatencyRequest, AMissingDeviceIsARefusalThatSaysWhy) {
  const CpuLatencyRequest request(0, "/nonexistent-livod-dir/cpu_dma_latency");
  EXPECT_FALSE(request.active());
  EXPECT_NE(request.refusal().find("realtime.cpu_dma_latency_us"), std::string::npos);
  EXPECT_NE(request.refusal().find("/nonexistent-livod-dir/cpu_dma_latency"), std::string::npos);
  EXPECT_NE(request.refusal().find("No such file"), std::string::npos) << request.refusal();
  EXPECT_TRUE(CpuLatencyRequest().refusal().empty());
  EXPECT_FALSE(CpuLatencyRequest().active());
}

// The kernel's own device where this process may write it (root, or a udev rule): reading it
// gives the effective bound of all requests, which is ours while we hold it (nobody asks for less
// than 0) and something larger again once released - unless another process holds a request of 0.
TEST(CpuLatencyRequest, TheKernelTakesTheRequestWhilePermitted) {
  if (::access(CpuLatencyRequest::kDevice, W_OK) != 0) {
    GTEST_SKIP() << CpuLatencyRequest::kDevice << " is not writable here";
  }
  auto effective = [] {
    const auto bytes = read_bytes(CpuLatencyRequest::kDevice);
    std::int32_t value = -1;
    if (bytes.size() == sizeof value) std::memcpy(&value, bytes.data(), sizeof value);
    return value;
  };
  const std::int32_t before = effective();
  {
    const CpuLatencyRequest request(0);
    ASSERT_TRUE(request.active()) << request.refusal();
    EXPECT_EQ(effective(), 0);
  }
  EXPECT_EQ(effective(), before);
}

}  // namespace
}  // namespace livod::daemon::runtime

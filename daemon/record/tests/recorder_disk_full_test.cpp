// The recorder on a full disk: a 1 MiB tmpfs mounted in a private mount namespace of this test
// process (root, as CI runs; `unshare -m` semantics, so nothing leaks to the machine), part of it
// taken by a filler file. The real monterey capture is streamed into the recorder's taps while it
// runs: blocks that do not fit are lost and counted with the reason, the file is cut back to its
// last complete block and stays readable by livod's pcap reader without any damage; once space is
// freed (the filler deleted) writing resumes, and the loss is one span between written stretches.

#include <gtest/gtest.h>
#include <sched.h>
#include <sys/mount.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "daemon/record/recorder.hpp"
#include "io/pcap.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon::record {
namespace {

struct Datagram {
  std::int64_t time_ns = 0;
  std::uint16_t dst_port = 0;
  std::vector<std::byte> payload;
  bool operator==(const Datagram&) const = default;
};

std::vector<Datagram> read_all(const std::filesystem::path& pcap, std::string& end_error,
                               std::size_t& damaged) {
  std::vector<Datagram> out;
  io::PcapReader reader(pcap);
  while (const auto d = reader.next()) {
    out.push_back({d->capture_time_ns, d->dst_port,
                   std::vector<std::byte>(d->payload.begin(), d->payload.end())});
  }
  end_error = reader.end_error();
  damaged = reader.losses().count();
  return out;
}

// A private mount namespace with a small tmpfs at `at`; the reason when it cannot be had.
std::string mount_small_tmpfs(const std::filesystem::path& at) {
  if (::unshare(CLONE_NEWNS) != 0)
    return std::string("unshare(CLONE_NEWNS): ") + std::strerror(errno);
  if (::mount("none", "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0) {
    return std::string("making / private: ") + std::strerror(errno);
  }
  if (::mount("livod-test", at.c_str(), "tmpfs", 0, "size=1m") != 0) {
    return std::string("mount tmpfs: ") + std::strerror(errno);
  }
  return {};
}

TEST(RecorderDiskFull, LosesWhatDoesNotFitCountsItAndResumesWhenSpaceIsFreed) {
  std::string end_error;
  std::size_t damaged = 0;
  std::vector<Datagram> capture;
  {
    io::PcapReader reader(test::data_path("velodyne/veloview/monterey-first-100-packets.pcap"));
    reader.set_port_filter({2368});
    while (const auto d = reader.next()) {
      capture.push_back({d->capture_time_ns, d->dst_port,
                         std::vector<std::byte>(d->payload.begin(), d->payload.end())});
    }
  }
  ASSERT_EQ(capture.size(), 2702U);  // 1206-byte payloads: 3.4 MB of frames

  const auto disk = test::temp_dir("recorder-disk-full");
  const std::string refused = mount_small_tmpfs(disk);
  ASSERT_TRUE(refused.empty()) << refused << " (the test needs root, as CI runs it)";
  {
    std::ofstream filler(disk / "filler", std::ios::binary);
    const std::vector<char> bytes(400 * 1024, 'x');
    filler.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }

  RecorderOptions options;
  options.dir = disk / "rec";
  options.block_bytes = 64 * 1024;
  options.flush_period = Nanoseconds(20'000'000);
  options.hold_back = Nanoseconds(0);
  options.retry_period = Nanoseconds(50'000'000);
  Recorder recorder(options);
  auto& tap = recorder.add_packet_stream({"hdl", "lidar", 1206, 0x7F000001});
  recorder.start();
  const auto push_range = [&](std::size_t from, std::size_t to) {
    for (std::size_t i = from; i < to; ++i) {
      const auto& d = capture[i];
      while (!tap.try_push(d.payload, HostTime(d.time_ns - recorder.realtime_offset_ns()),
                           d.dst_port)) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));  // never lose to the tap here
      }
    }
    // Let the recorder write (or fail to write) everything queued.
    while (tap.size_approx() > 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  };
  // 1500 packets (~1.9 MB of records) on ~600 KB free: the disk fills.
  push_range(0, 1500);
  const auto during = recorder.stats().at(0);
  EXPECT_GT(during.lost_write_failed, 0U);
  EXPECT_NE(during.last_error.find("No space left on device"), std::string::npos)
      << during.last_error;
  // Space comes back: the rest is written.
  std::filesystem::remove(disk / "filler");
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  push_range(1500, 1750);
  const auto problems = recorder.stop();
  ASSERT_EQ(problems.size(), 1U);
  EXPECT_NE(problems[0].find("write failed"), std::string::npos) << problems[0];

  const auto stats = recorder.stats().at(0);
  EXPECT_EQ(stats.packets + stats.lost(), 1750U);
  EXPECT_EQ(stats.lost(), stats.lost_write_failed);
  EXPECT_GT(stats.packets, 400U);
  // One span of loss (merged), no more: between what was written before and after.
  ASSERT_EQ(stats.losses.size(), 1U);
  EXPECT_EQ(stats.losses[0].packets, stats.lost_write_failed);
  EXPECT_NE(stats.losses[0].reason.find("No space left on device"), std::string::npos);

  // The file: readable to its end, no damage, exactly the written packets, in order, each one
  // of the capture; the lost ones are the stretch the loss span names.
  const auto recorded = read_all(options.dir / "hdl.pcap", end_error, damaged);
  EXPECT_TRUE(end_error.empty()) << end_error;
  EXPECT_EQ(damaged, 0U);
  ASSERT_EQ(recorded.size(), stats.packets);
  EXPECT_EQ(std::filesystem::file_size(options.dir / "hdl.pcap"), stats.file_bytes);
  std::size_t at = 0;
  std::size_t skipped = 0;
  for (const auto& r : recorded) {
    while (at < 1750 && !(capture[at] == r)) {
      EXPECT_GE(capture[at].time_ns, stats.losses[0].first_ns);
      EXPECT_LE(capture[at].time_ns, stats.losses[0].last_ns);
      ++at;
      ++skipped;
    }
    ASSERT_LT(at, 1750U) << "a recorded datagram that is not the capture's next";
    ++at;
  }
  EXPECT_EQ(skipped + (1750 - at), stats.lost_write_failed);
  EXPECT_EQ(recorded.back(), capture[1749]) << "written again once space was freed";
  std::printf("[disk full] %llu packets written, %llu lost (write failed), file %llu bytes\n",
              static_cast<unsigned long long>(stats.packets),
              static_cast<unsigned long long>(stats.lost_write_failed),
              static_cast<unsigned long long>(stats.file_bytes));
}

}  // namespace
}  // namespace livod::daemon::record

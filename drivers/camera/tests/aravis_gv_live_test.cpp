// The Aravis backend against a real GigE Vision device simulator, `arv-fake-gv-camera-0.8`, on
// loopback inside a private network namespace (nothing leaves the machine): discovery, control
// (region, frame rate, exposure, packet size), streaming at 1280x1024 mono 30 Hz, exposure changes
// reflected in the frames' metadata, software trigger, lost packets counted, and the camera
// process killed and restarted -> STALE -> reconnected by the running source.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <net/if.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <thread>

#include "core/error.hpp"
#include "drivers/camera/aravis_camera.hpp"
#include "drivers/camera/camera_source.hpp"

extern char** environ;

namespace livod::camera {
namespace {

using namespace std::chrono_literals;

constexpr const char* kCameraId = "Aravis-Fake-GV01";

// The GigE Vision simulator as a child process (in this process's network namespace).
class FakeGvCamera {
 public:
  explicit FakeGvCamera(int lost_per_thousand = 0) { start(lost_per_thousand); }
  ~FakeGvCamera() { kill(); }
  void start(int lost_per_thousand = 0) {
    const std::string ratio = std::to_string(lost_per_thousand);
    std::vector<const char*> argv{"arv-fake-gv-camera-0.8", "-i", "127.0.0.1", "-s", "GV01"};
    if (lost_per_thousand > 0) {
      argv.push_back("-r");
      argv.push_back(ratio.c_str());
    }
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
    const int rc = posix_spawnp(&pid_, argv[0], &actions, nullptr,
                                const_cast<char* const*>(argv.data()), environ);
    posix_spawn_file_actions_destroy(&actions);
    ASSERT_EQ(rc, 0) << "cannot start arv-fake-gv-camera-0.8 (aravis-tools installed?)";
  }
  void kill() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }

 private:
  pid_t pid_ = -1;
};

class AravisGv : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // A private network namespace with only a loopback interface: GVCP discovery broadcasts and
    // GVSP streams stay inside it. Threads created afterwards (capture, Aravis) inherit it.
    ASSERT_EQ(::unshare(CLONE_NEWNET), 0) << "unshare(CLONE_NEWNET): " << std::strerror(errno);
    const int s = ::socket(AF_INET, SOCK_DGRAM, 0);
    ifreq ifr{};
    std::strncpy(ifr.ifr_name, "lo", IFNAMSIZ - 1);
    ASSERT_EQ(::ioctl(s, SIOCGIFFLAGS, &ifr), 0);
    ifr.ifr_flags = static_cast<short>(ifr.ifr_flags | IFF_UP);
    ASSERT_EQ(::ioctl(s, SIOCSIFFLAGS, &ifr), 0);
    ::close(s);
  }

  static AravisCameraConfig config() {
    AravisCameraConfig c;
    c.camera_id = kCameraId;
    c.width = 1280;
    c.height = 1024;
    c.frame_rate_hz = 30.0;
    c.buffers = 8;
    return c;
  }
  static CameraSourceConfig source_config() {
    CameraSourceConfig s;
    s.name = "gige";
    s.width = 1280;
    s.height = 1024;
    s.ring_capacity = 8;
    s.stale_after = 700ms;
    s.thread.poll_timeout = 10ms;
    s.thread.reopen_interval = 200ms;
    return s;
  }
  // The simulator needs a moment to answer discovery: retry the open for up to 10 s.
  static std::unique_ptr<CameraSource> open(const AravisCameraConfig& c,
                                            const CameraSourceConfig& s) {
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    for (;;) {
      try {
        return std::make_unique<CameraSource>(s, std::make_unique<AravisCamera>(c));
      } catch (const Error& e) {
        if (std::chrono::steady_clock::now() > deadline) throw;
        std::this_thread::sleep_for(200ms);
      }
    }
  }
};

template <class Cond>
bool wait_until(CameraSource& source, const CameraSource::FrameCallback& cb, Cond&& cond,
                std::chrono::seconds limit = 20s) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < deadline) {
    source.poll(cb);
    if (cond()) return true;
    std::this_thread::sleep_for(5ms);
  }
  return cond();
}

TEST_F(AravisGv, DiscoversControlsAndStreamsAtTheConfiguredRateWithExposureMetadata) {
  FakeGvCamera fake;
  auto cfg = config();
  cfg.exposure = 6ms;
  auto source = open(cfg, source_config());
  const auto& backend = static_cast<const AravisCamera&>(source->backend());
  EXPECT_EQ(backend.status().serial, "GV01");
  EXPECT_EQ(backend.status().model, "Aravis Fake");
  EXPECT_GT(backend.status().packet_size, 500);  // negotiated
  std::vector<FrameInfo> infos;
  const auto cb = [&](const CameraFrame& f) {
    infos.push_back(f.info);
    EXPECT_EQ(f.image.cols, 1280);
    EXPECT_EQ(f.image.rows, 1024);
  };
  ASSERT_TRUE(wait_until(*source, cb, [&] { return infos.size() >= 45; }));
  // The camera accepted 30 Hz; the rate seen in its own clock and block ids does not exceed it by
  // more than the stamps' jitter. (It can fall below: the simulator is a process on the same
  // loaded cores, and a rate floor would be a timing assertion.) The fake stamps a frame when its
  // process sends it, so on loaded cores the first stamp can be up to a frame period late and the
  // measured span one interval short (a full CI-style run measured 30.53 Hz over 44 intervals);
  // a camera at twice the rate still fails.
  EXPECT_NEAR(backend.status().frame_rate_hz, 30.0, 0.01);
  const auto& a = infos.front();
  const auto& b = infos.back();
  const double intervals = static_cast<double>(b.sequence - a.sequence);
  const double rate = intervals / ((b.sensor_time - a.sensor_time).count() * 1e-9);
  ASSERT_GT(intervals, 1.0);
  EXPECT_LE(rate, 30.0 * intervals / (intervals - 1.0));
  EXPECT_GT(rate, 0.0);
  EXPECT_EQ(b.exposure, 6ms);
  EXPECT_EQ(b.clock, CameraClockKind::kDevice);

  source->set_exposure(3ms);
  const std::size_t before = infos.size();
  ASSERT_TRUE(wait_until(
      *source, cb, [&] { return infos.size() > before + 3 && infos.back().exposure == 3ms; }));
  const auto h = source->update_health(host_now());
  EXPECT_EQ(h.source.streams.at(0).state, drivers::capture::StreamState::kStreaming);
  EXPECT_EQ(h.backend.exposure_ns, 3'000'000);
  EXPECT_EQ(h.backend.control_errors, 0u);
}

TEST_F(AravisGv, SoftwareTriggeredFramesFollowTheHostsTriggers) {
  FakeGvCamera fake;
  auto cfg = config();
  cfg.trigger = TriggerMode::kSoftware;
  cfg.frame_rate_hz = 5.0;  // livod triggers at 5 Hz; the camera free-runs at 25 Hz otherwise
  CameraSourceConfig s = source_config();
  s.reopen_on_silence = true;
  auto source = open(cfg, s);
  std::vector<FrameInfo> infos;
  const auto start = std::chrono::steady_clock::now();
  ASSERT_TRUE(wait_until(
      *source, [&](const CameraFrame& f) { infos.push_back(f.info); },
      [&] { return std::chrono::steady_clock::now() - start > 2s; }));
  const auto c = source->backend_counters();
  EXPECT_GE(c.triggers, 8u);
  EXPECT_LE(infos.size(), c.triggers);
  EXPECT_GE(infos.size() + 2, c.triggers);  // the newest triggers may still be in flight
  for (const auto& i : infos) {
    EXPECT_GT(i.trigger_host_ns, 0);
    EXPECT_LT(i.trigger_host_ns, i.host_rx.ns);
  }
}

TEST_F(AravisGv, LostPacketsWithoutResendAreCountedAndDropped) {
  FakeGvCamera fake(20);  // 2 % of GVSP packets lost
  auto cfg = config();
  cfg.width = 640;
  cfg.height = 480;
  cfg.packet_resend = false;
  cfg.packet_size = 1500;
  CameraSourceConfig s = source_config();
  s.width = 640;
  s.height = 480;
  auto source = open(cfg, s);
  EXPECT_EQ(static_cast<const AravisCamera&>(source->backend()).status().packet_size, 1500);
  std::size_t good = 0;
  ASSERT_TRUE(wait_until(
      *source, [&](const CameraFrame&) { ++good; },
      [&] { return source->backend_counters().frames >= 40; }));
  const auto c = source->backend_counters();
  // 640 x 480 / ~1470 B per packet: ~210 packets per frame, 2 % lost: nearly every frame is
  // incomplete; the complete ones are delivered.
  EXPECT_GT(c.incomplete, 10u);
  EXPECT_EQ(c.incomplete + good + source->ring_overruns(), c.frames) << good;
}

TEST_F(AravisGv, ACameraKilledAndRestartedGoesStaleAndIsReconnected) {
  auto fake = std::make_unique<FakeGvCamera>();
  auto cfg = config();
  cfg.width = 640;
  cfg.height = 480;
  CameraSourceConfig s = source_config();
  s.width = 640;
  s.height = 480;
  auto source = open(cfg, s);
  std::size_t frames = 0;
  const auto cb = [&](const CameraFrame&) { ++frames; };
  ASSERT_TRUE(wait_until(*source, cb, [&] { return frames >= 10; }));

  fake->kill();
  const auto killed = std::chrono::steady_clock::now();
  ASSERT_TRUE(wait_until(*source, cb, [&] { return source->device_counters().losses >= 1; }));
  std::printf("loss detected after %.2f s\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - killed).count());
  std::this_thread::sleep_for(800ms);
  auto h = source->update_health(host_now());
  EXPECT_EQ(h.source.streams.at(0).state, drivers::capture::StreamState::kStale);
  EXPECT_NE(h.source.device_state, "STREAMING");
  EXPECT_FALSE(h.source.last_error.empty());

  fake->start();
  const auto restarted = std::chrono::steady_clock::now();
  const std::size_t before = frames;
  ASSERT_TRUE(wait_until(
      *source, cb,
      [&] { return source->device_counters().reconnects >= 1 && frames >= before + 10; }, 30s))
      << source->update_health(host_now()).source.last_error;
  std::printf("streaming again %.2f s after the restart\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - restarted).count());
  h = source->update_health(host_now());
  EXPECT_EQ(h.source.streams.at(0).state, drivers::capture::StreamState::kStreaming);
  EXPECT_GE(h.source.streams.at(0).stale_events, 1u);
  EXPECT_GE(h.source.streams.at(0).recoveries, 1u);
  EXPECT_GE(h.source.reconnects, 1u);
}

}  // namespace
}  // namespace livod::camera

// CameraSource end to end with real threads on recorded V4L2 buffers: capture thread -> frame ring
// -> consumer with the clock mapping; a camera that is unplugged (STALE/LOST) and plugged back
// (reopened by the running source); a full ring; decimation; exposure changed while streaming.

#include "drivers/camera/camera_source.hpp"

#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <chrono>
#include <thread>

#include "core/error.hpp"
#include "drivers/camera/v4l2_camera.hpp"
#include "drivers/camera/v4l2_recorded.hpp"

namespace livod::camera {
namespace {

using namespace std::chrono_literals;

constexpr int kW = 64;
constexpr int kH = 48;
constexpr std::uint32_t kFlags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_SOE;

// Frame k: every pixel = k mod 256, stamped k x 33 ms after 1000 s.
std::vector<RecordedBuffer> frames(int first, int count) {
  std::vector<RecordedBuffer> out;
  for (int k = first; k < first + count; ++k) {
    out.push_back({std::vector<std::uint8_t>(kW * kH, static_cast<std::uint8_t>(k & 0xFF)),
                   static_cast<std::uint32_t>(k), 1'000'000'000'000 + std::int64_t{k} * 33'000'000,
                   kFlags});
  }
  return out;
}

V4l2Recording rec(int count) {
  V4l2Recording r;
  r.formats = {V4L2_PIX_FMT_GREY};
  r.width = kW;
  r.height = kH;
  r.frames = frames(0, count);
  r.pace = 1ms;
  return r;
}

CameraSourceConfig source_config(std::size_t ring) {
  CameraSourceConfig c;
  c.name = "cam0";
  c.width = kW;
  c.height = kH;
  c.ring_capacity = ring;
  c.stale_after = 150ms;
  c.thread.poll_timeout = 5ms;
  c.thread.reopen_interval = 20ms;
  return c;
}

std::unique_ptr<V4l2Camera> backend(std::shared_ptr<RecordedV4l2Device> dev,
                                    std::optional<Nanoseconds> exposure = std::nullopt) {
  V4l2CameraConfig c;
  c.path = "/dev/video0";
  c.width = kW;
  c.height = kH;
  c.exposure = exposure;
  return std::make_unique<V4l2Camera>(c, std::move(dev));
}

template <class Poll, class Cond>
bool wait_for(Poll&& poll, Cond&& cond) {
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (std::chrono::steady_clock::now() < deadline) {
    poll();
    if (cond()) return true;
    std::this_thread::sleep_for(2ms);
  }
  poll();
  return cond();
}

struct Seen {
  std::uint64_t sequence;
  std::uint8_t pixel;
  std::int64_t mid_ns;
  Nanoseconds exposure;
};

TEST(CameraSourceThreads, FramesFlowAndACameraUnpluggedAndPluggedBackIsReopened) {
  auto dev = std::make_shared<RecordedV4l2Device>(rec(40));
  CameraSource source(source_config(16), backend(dev, 10ms));
  std::vector<Seen> seen;
  auto poll = [&] {
    source.poll([&](const CameraFrame& f) {
      seen.push_back({f.info.sequence, f.image.at<std::uint8_t>(kH - 1, kW - 1), f.mid_exposure.ns,
                      f.info.exposure});
    });
  };
  ASSERT_TRUE(wait_for(poll, [&] { return seen.size() == 40; })) << seen.size();
  for (std::size_t k = 0; k < seen.size(); ++k) {
    EXPECT_EQ(seen[k].sequence, k);
    EXPECT_EQ(seen[k].pixel, k & 0xFF);
    EXPECT_EQ(seen[k].mid_ns,
              1'000'000'000'000 + static_cast<std::int64_t>(k) * 33'000'000 + 5'000'000);
    EXPECT_EQ(seen[k].exposure, 10ms);
  }
  auto h = source.update_health(host_now());
  EXPECT_EQ(h.source.device_state, "STREAMING");
  EXPECT_EQ(h.backend.frames, 40u);
  EXPECT_EQ(h.delivered, 40u);
  EXPECT_EQ(h.ring_overruns, 0u);

  // Unplugged: the capture thread sees ENODEV, closes the device, retries the open.
  dev->unplug();
  ASSERT_TRUE(wait_for(poll, [&] { return source.device_counters().open_failures >= 2; }))
      << "opens " << source.device_counters().opens << " losses " << source.device_counters().losses
      << " state " << drivers::capture::to_string(source.device_counters().state) << " error "
      << source.update_health(host_now()).source.last_error;
  EXPECT_EQ(source.device_counters().state, drivers::capture::DeviceState::kLost);
  std::this_thread::sleep_for(200ms);
  h = source.update_health(host_now());
  EXPECT_EQ(h.source.streams.at(0).state, drivers::capture::StreamState::kStale);
  EXPECT_NE(h.source.last_error.find("/dev/video0"), std::string::npos) << h.source.last_error;

  // Plugged back: reopened (format, exposure, buffers again) and streaming, nothing restarted.
  dev->add_frames(frames(40, 20));
  dev->plug();
  ASSERT_TRUE(wait_for(poll, [&] { return seen.size() == 60; })) << seen.size();
  EXPECT_EQ(seen.back().sequence, 59u);
  EXPECT_EQ(dev->opens(), 2);
  h = source.update_health(host_now());
  EXPECT_EQ(h.source.streams.at(0).state, drivers::capture::StreamState::kStreaming);
  EXPECT_EQ(h.source.reconnects, 1u);
  EXPECT_EQ(h.source.streams.at(0).stale_events, 1u);
  EXPECT_EQ(h.device.losses, 1u);
  EXPECT_EQ(h.backend.exposure_ns, 10'000'000);
}

TEST(CameraSourceThreads, ASilentCameraIsReopenedAfterStaleAfter) {
  auto dev = std::make_shared<RecordedV4l2Device>(rec(5));
  CameraSource source(source_config(8), backend(dev));
  std::size_t n = 0;
  auto poll = [&] { n += source.poll({}); };
  ASSERT_TRUE(wait_for(poll, [&] { return n == 5; }));
  // No more frames: after stale_after (150 ms) the source closes and reopens the device.
  ASSERT_TRUE(wait_for(poll, [&] { return source.device_counters().reconnects >= 1; }));
  EXPECT_GE(dev->opens(), 2);
  EXPECT_NE(source.update_health(host_now()).source.last_error.find("no data"), std::string::npos);
}

TEST(CameraSourceThreads, AFullRingDropsNewFramesAndDecimationSkipsCopies) {
  auto fast = rec(30);
  fast.pace = 0ms;
  auto dev = std::make_shared<RecordedV4l2Device>(fast);
  CameraSource source(source_config(4), backend(dev));
  // Nobody polls: 4 frames fit, 26 are dropped and counted.
  ASSERT_TRUE(wait_for([] {}, [&] { return source.backend_counters().frames == 30; }));
  EXPECT_EQ(source.ring_overruns(), 26u);
  std::vector<std::uint64_t> seq;
  source.poll([&](const CameraFrame& f) { seq.push_back(f.info.sequence); });
  EXPECT_EQ(seq, (std::vector<std::uint64_t>{0, 1, 2, 3}));  // the oldest, intact

  auto dev2 = std::make_shared<RecordedV4l2Device>(rec(30));
  CameraSourceConfig c = source_config(16);
  c.decimation = 3;
  CameraSource decimated(c, backend(dev2));
  std::vector<std::uint64_t> kept;
  ASSERT_TRUE(wait_for(
      [&] { decimated.poll([&](const CameraFrame& f) { kept.push_back(f.info.sequence); }); },
      [&] { return kept.size() == 10; }));
  ASSERT_TRUE(wait_for([] {}, [&] { return decimated.backend_counters().frames == 30; }));
  EXPECT_EQ(kept.front(), 0u);
  EXPECT_EQ(kept.back(), 27u);
  EXPECT_EQ(decimated.update_health(host_now()).decimated, 20u);
}

TEST(CameraSourceThreads, ExposureChangesWhileStreamingReachTheFrames) {
  auto dev = std::make_shared<RecordedV4l2Device>(rec(3));
  CameraSource source(source_config(16), backend(dev, 10ms));
  std::vector<Nanoseconds> exposures;
  auto poll = [&] {
    source.poll([&](const CameraFrame& f) { exposures.push_back(f.info.exposure); });
  };
  ASSERT_TRUE(wait_for(poll, [&] { return exposures.size() == 3; }));
  source.set_exposure(2500us);
  ASSERT_TRUE(wait_for([] {}, [&] { return dev->exposure_100us() == 25; }));
  dev->add_frames(frames(3, 2));
  ASSERT_TRUE(wait_for(poll, [&] { return exposures.size() == 5; }));
  EXPECT_EQ(exposures[2], 10ms);
  EXPECT_EQ(exposures[3], 2500us);
  EXPECT_EQ(exposures[4], 2500us);
}

TEST(CameraSourceThreads, AMissingCameraFailsAtConstructionNamingIt) {
  auto dev = std::make_shared<RecordedV4l2Device>(rec(1));
  V4l2CameraConfig c;
  c.path = "/dev/video3";
  c.width = kW;
  c.height = kH;
  try {
    CameraSource source(source_config(4), std::make_unique<V4l2Camera>(c, dev));
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "V4L2 device /dev/video3: does not exist");
  }
}

}  // namespace
}  // namespace livod::camera

// The runtime's live camera source (live_camera_source.hpp) with its real capture thread on
// Aravis's in-process fake camera: what the scheduler sees through MeasurementSource — frames
// already on the host timeline at mid-exposure, in receive-time order, ringing the doorbell.
// Not a *_threads_test: GLib/Aravis are not instrumented for ThreadSanitizer.

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "core/image.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/runtime/live_camera_source.hpp"
#include "daemon/runtime/tests/live_source_test_support.hpp"
#include "drivers/camera/aravis_camera.hpp"

namespace livod::daemon::runtime {
namespace {

using namespace std::chrono_literals;

using test_support::drain;
using test_support::kExtrinsic;
using test_support::kLidar;
using test_support::load_runnable;

TEST(LiveCameraSource, ACameraDeliversMappedFramesAtMidExposureInReceiveOrder) {
  camera::AravisCamera::enable_fake_interface();
  const auto config = load_runnable("body_frame: mti\nsensors:\n" + kLidar + R"(  - name: mti
    driver: serial_imu
    source: {device: {path: /dev/ttyUSB0}}
    serial: {protocol: xsens_mtdata2}
  - name: cam
    driver: aravis
    source: {device: {camera_id: Fake_1}}
    time_offset_s: 0.0
    camera: {width: 320, height: 240, intrinsics: [300, 300, 160, 120], exposure_s: 0.004,
             frame_rate_hz: 50, pixel_format: mono8, buffers: 4}
)" + kExtrinsic);
  drivers::capture::Doorbell doorbell;
  const std::uint32_t token = doorbell.prepare();
  auto source = open_live_camera(*config.find_sensor("cam"), config, &doorbell);
  EXPECT_TRUE(source->delivers_mapped_images());
  const auto threads = source->threads();
  ASSERT_EQ(threads.size(), 1u);
  EXPECT_EQ(threads[0].name, "cam.frames");
  const std::uint64_t beats0 = threads[0].beats();

  std::vector<ImageFrame> frames;
  std::vector<std::int64_t> peeked;
  std::vector<std::int64_t> delivered_at;
  drivers::DecoderSinks sinks;
  sinks.on_image = [&](const ImageFrame& f) {
    frames.push_back(f);
    delivered_at.push_back(host_now().ns);
  };
  ASSERT_TRUE(drain(
      *source, sinks, [&] { return frames.size() >= 20; }, &peeked));
  EXPECT_GT(threads[0].beats(), beats0);
  EXPECT_NE(doorbell.prepare(), token) << "frames ring the scheduler's doorbell";
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const ImageFrame& f = frames[i];
    EXPECT_EQ(f.image.cols, 320);
    EXPECT_EQ(f.image.rows, 240);
    EXPECT_EQ(f.image.type(), CV_8UC1);
    EXPECT_EQ(f.exposure, 4ms);
    // On the host timeline at mid-exposure: before the frame was received, not long before.
    EXPECT_EQ((f.mid_exposure - f.trigger_time).count(), 2'000'000);
    EXPECT_LT(f.mid_exposure.ns, f.stamp.host.ns);
    EXPECT_LT(f.stamp.host.ns - f.mid_exposure.ns, 200'000'000) << i;
    EXPECT_LE(f.stamp.host.ns, delivered_at[i]);
    EXPECT_EQ(peeked[i], f.stamp.host.ns);  // merged on the receive time
    if (i > 0) {
      EXPECT_GT(f.mid_exposure, frames[i - 1].mid_exposure);
      EXPECT_GT(f.stamp.host, frames[i - 1].stamp.host);
    }
  }
  const auto h = source->health(host_now());
  ASSERT_TRUE(h);
  EXPECT_EQ(h->streams.at(0).state, drivers::capture::StreamState::kStreaming);
  EXPECT_EQ(h->device_state, "STREAMING");
  EXPECT_GE(h->decoder.packets, 20u);
  ASSERT_TRUE(source->clock_stats());
  EXPECT_NE(source->summary().find("device STREAMING"), std::string::npos) << source->summary();

  // Stopped: what the ring still holds drains, then the source is exhausted.
  source->stop();
  while (source->peek_time()) source->deliver(sinks);
  EXPECT_TRUE(source->exhausted());
}

}  // namespace
}  // namespace livod::daemon::runtime

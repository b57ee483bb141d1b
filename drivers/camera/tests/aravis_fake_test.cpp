// The Aravis backend against Aravis's in-process fake camera ("Fake_1", the Fake interface):
// discovery, format control, streaming through a CameraSource, exposure changes reflected in the
// frames, clear failures. (The in-process fake free-runs whatever the trigger mode; triggers,
// packets and reconnection are tested against the GigE Vision fake camera in
// aravis_gv_live_test.)

#include "drivers/camera/aravis_camera.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <opencv2/core.hpp>
#include <thread>

#include "core/error.hpp"
#include "drivers/camera/camera_source.hpp"

namespace livod::camera {
namespace {

using namespace std::chrono_literals;

class AravisFake : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { AravisCamera::enable_fake_interface(); }

  static AravisCameraConfig config(PixelFormat f = PixelFormat::kMono8) {
    AravisCameraConfig c;
    c.camera_id = "Fake_1";
    c.width = 320;
    c.height = 240;
    c.format = f;
    c.frame_rate_hz = 50.0;
    c.buffers = 4;
    return c;
  }
  static CameraSourceConfig source_config(PixelFormat f = PixelFormat::kMono8) {
    CameraSourceConfig s;
    s.name = "gige";
    s.width = 320;
    s.height = 240;
    s.format = f;
    s.ring_capacity = 8;
    s.thread.poll_timeout = 10ms;
    return s;
  }
};

template <class Cond>
bool wait_until(CameraSource& source, const CameraSource::FrameCallback& cb, Cond&& cond) {
  const auto deadline = std::chrono::steady_clock::now() + 15s;
  while (std::chrono::steady_clock::now() < deadline) {
    source.poll(cb);
    if (cond()) return true;
    std::this_thread::sleep_for(5ms);
  }
  return cond();
}

TEST_F(AravisFake, StreamsFramesWithDeviceTimestampsAndExposureMetadata) {
  auto cfg = config();
  cfg.exposure = 8ms;
  CameraSource source(source_config(), std::make_unique<AravisCamera>(cfg));
  std::vector<FrameInfo> infos;
  std::vector<double> brightness;
  std::vector<std::int64_t> mid;
  const auto cb = [&](const CameraFrame& f) {
    infos.push_back(f.info);
    brightness.push_back(cv::mean(f.image)[0]);
    mid.push_back(f.mid_exposure.ns);
    EXPECT_EQ(f.image.cols, 320);
    EXPECT_EQ(f.image.rows, 240);
  };
  ASSERT_TRUE(wait_until(source, cb, [&] { return infos.size() >= 20; }));
  for (std::size_t i = 1; i < infos.size(); ++i) {
    EXPECT_EQ(infos[i].sequence, infos[i - 1].sequence + 1);
    EXPECT_GT(infos[i].sensor_time, infos[i - 1].sensor_time);
    EXPECT_GT(mid[i], mid[i - 1]);
  }
  EXPECT_EQ(infos.back().clock, CameraClockKind::kDevice);
  EXPECT_EQ(infos.back().exposure, 8ms);
  EXPECT_EQ(infos.back().exposure_source, ExposureSource::kReadback);
  // The device clock is mapped onto CLOCK_MONOTONIC: mid-exposure lies before the receive time.
  EXPECT_LT(mid.back(), infos.back().host_rx.ns);
  EXPECT_GT(mid.back(), infos.back().host_rx.ns - 1'000'000'000);

  // A new exposure reaches the camera and the following frames' metadata.
  source.set_exposure(2ms);
  const std::size_t before = infos.size();
  ASSERT_TRUE(wait_until(
      source, cb, [&] { return infos.size() > before + 5 && infos.back().exposure == 2ms; }));
  EXPECT_EQ(source.backend_counters().exposure_ns, 2'000'000);
  const auto h = source.update_health(host_now());
  EXPECT_EQ(h.source.device_state, "STREAMING");
  EXPECT_EQ(h.backend.incomplete, 0u);
  EXPECT_EQ(h.backend.sequence_gaps, 0u);
  ASSERT_TRUE(h.clock);
  EXPECT_EQ(h.clock->mode, ClockMode::free_running);
}

TEST_F(AravisFake, PixelFormatsConvertFromWhatTheCameraOffers) {
  // The fake camera offers Mono8, Mono16, RGB8 and Bayer: bgr8 comes from RGB8, mono16 direct.
  for (const PixelFormat f : {PixelFormat::kBgr8, PixelFormat::kMono16}) {
    auto cfg = config(f);
    CameraSource source(source_config(f), std::make_unique<AravisCamera>(cfg));
    int type = -1;
    ASSERT_TRUE(wait_until(
        source, [&](const CameraFrame& fr) { type = fr.image.type(); },
        [&] { return type != -1; }));
    EXPECT_EQ(type, cv_type(f));
  }
}

TEST_F(AravisFake, MissingCameraAndUnsupportedFeaturesFailAtOpen) {
  auto missing = config();
  missing.camera_id = "Basler-acA1920-4711";
  try {
    CameraSource source(source_config(), std::make_unique<AravisCamera>(missing));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'Basler-acA1920-4711' not found"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("Fake_1"), std::string::npos) << e.what();
  }
  auto ptp = config();
  ptp.ptp = true;
  try {
    CameraSource source(source_config(), std::make_unique<AravisCamera>(ptp));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("has no PTP"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace livod::camera

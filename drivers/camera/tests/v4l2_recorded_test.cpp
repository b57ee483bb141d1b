// The real V4L2 backend on recorded buffers (RecordedV4l2Device answers the ioctls): format
// negotiation, conversion of every wire format from real EuRoC images, buffer timestamps and their
// flags, sequence gaps, error buffers, exposure control and readback, clear open failures.

#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/error.hpp"
#include "core/realtime_offset.hpp"
#include "drivers/camera/camera_clock.hpp"
#include "drivers/camera/frame_ring.hpp"
#include "drivers/camera/v4l2_camera.hpp"
#include "drivers/camera/v4l2_recorded.hpp"
#include "io/euroc_image.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::camera {
namespace {

// Two real 752x480 frames of EuRoC V1_01 cam0.
std::vector<cv::Mat> euroc_frames() {
  const auto dir = test::data_path("euroc_v101/mav0/cam0/data");
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return {io::load_dataset_image(files.at(10), io::ImageDecodeMode::kMono8),
          io::load_dataset_image(files.at(40), io::ImageDecodeMode::kMono8)};
}

std::vector<std::uint8_t> bytes_of(const cv::Mat& m) {
  const cv::Mat c = m.isContinuous() ? m : m.clone();
  return {c.data, c.data + c.total() * c.elemSize()};
}

// The wire image of a grey picture in each format.
std::vector<std::uint8_t> encode(const cv::Mat& grey, std::uint32_t fourcc) {
  switch (fourcc) {
    case V4L2_PIX_FMT_GREY:
      return bytes_of(grey);
    case V4L2_PIX_FMT_YUYV: {
      cv::Mat yuyv(grey.rows, grey.cols, CV_8UC2);
      for (int r = 0; r < grey.rows; ++r) {
        for (int c = 0; c < grey.cols; ++c) {
          yuyv.at<cv::Vec2b>(r, c) = {grey.at<std::uint8_t>(r, c), 128};
        }
      }
      return bytes_of(yuyv);
    }
    case V4L2_PIX_FMT_Y16: {
      cv::Mat y16(grey.rows, grey.cols, CV_16UC1);
      for (int r = 0; r < grey.rows; ++r) {
        for (int c = 0; c < grey.cols; ++c) {
          y16.at<std::uint16_t>(r, c) =
              static_cast<std::uint16_t>((grey.at<std::uint8_t>(r, c) << 8) | ((r * 7 + c) & 0x7F));
        }
      }
      return bytes_of(y16);
    }
    case V4L2_PIX_FMT_BGR24: {
      cv::Mat bgr;
      cv::cvtColor(grey, bgr, cv::COLOR_GRAY2BGR);
      return bytes_of(bgr);
    }
    case V4L2_PIX_FMT_MJPEG: {
      std::vector<std::uint8_t> jpeg;
      cv::imencode(".jpg", grey, jpeg, {cv::IMWRITE_JPEG_QUALITY, 95});
      return jpeg;
    }
    default:
      return {};
  }
}

constexpr std::uint32_t kMonoSoe = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_SOE;

V4l2Recording recording(const std::vector<cv::Mat>& images, std::uint32_t fourcc,
                        std::vector<std::uint32_t> offered = {}) {
  V4l2Recording rec;
  rec.formats = offered.empty() ? std::vector<std::uint32_t>{fourcc} : offered;
  rec.width = images.at(0).cols;
  rec.height = images.at(0).rows;
  for (std::size_t i = 0; i < images.size(); ++i) {
    rec.frames.push_back({encode(images[i], fourcc), static_cast<std::uint32_t>(i),
                          5'000'000'000 + static_cast<std::int64_t>(i) * 50'000'000, kMonoSoe});
  }
  return rec;
}

// The ring side of a source, driven by hand.
class TestSink final : public FrameSink {
 public:
  TestSink(int w, int h, PixelFormat f)
      : ring(8, static_cast<std::size_t>(w) * h * bytes_per_pixel(f)), format(f) {}
  cv::Mat acquire(int width, int height) override {
    const auto slot = ring.begin_write();
    if (slot.empty()) return {};
    return cv::Mat(height, width, cv_type(format), slot.data());
  }
  void commit(const FrameInfo& info) override { ring.commit(info); }
  // The next frame, mapped with `clock`.
  std::optional<CameraFrame> take(CameraClock& clock) {
    const auto* e = ring.front();
    if (e == nullptr) return std::nullopt;
    CameraFrame f;
    f.info = e->info;
    f.image = cv::Mat(e->info.height, e->info.width, cv_type(e->info.format),
                      const_cast<std::byte*>(e->pixels.data()), e->info.stride)
                  .clone();
    clock.map(f);
    ring.pop();
    return f;
  }
  FrameRing ring;
  PixelFormat format;
};

// Opens a backend on `rec`, pulls every frame; returns the frames and the backend counters.
struct RunResult {
  std::vector<CameraFrame> frames;
  CameraBackendCounters counters;
  std::optional<WireFormat> wire;
};

RunResult run(V4l2Recording rec, V4l2CameraConfig cfg, CameraClockConfig clock_cfg = {}) {
  auto dev = std::make_shared<RecordedV4l2Device>(rec);
  cfg.path = rec.path;
  if (cfg.width == 0) cfg.width = rec.width;
  if (cfg.height == 0) cfg.height = rec.height;
  V4l2Camera cam(cfg, dev);
  cam.open();
  TestSink sink(cfg.width, cfg.height, cfg.format);
  CameraClock clock(clock_cfg);
  RunResult r;
  for (std::size_t i = 0; i < rec.frames.size() + 2; ++i) {
    cam.next_frame(std::chrono::milliseconds(1), sink);
    while (auto f = sink.take(clock)) r.frames.push_back(*f);
  }
  r.counters = cam.counters();
  r.wire = cam.wire_format();
  cam.close();
  return r;
}

double mean_abs_diff(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat d;
  cv::absdiff(a, b, d);
  return cv::mean(d)[0];
}

TEST(V4l2Recorded, EveryWireFormatConvertsRealImagesIntoTheRing) {
  const auto images = euroc_frames();
  ASSERT_EQ(images[0].cols, 752);
  for (const std::uint32_t f : {V4L2_PIX_FMT_GREY, V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_Y16,
                                V4L2_PIX_FMT_BGR24, V4L2_PIX_FMT_MJPEG}) {
    SCOPED_TRACE(fourcc_name(f));
    V4l2CameraConfig cfg;
    cfg.format = PixelFormat::kMono8;
    const RunResult r = run(recording(images, f), cfg);
    ASSERT_EQ(r.frames.size(), 2u);
    EXPECT_EQ(r.counters.convert_errors, 0u);
    for (std::size_t i = 0; i < 2; ++i) {
      const cv::Mat& got = r.frames[i].image;
      ASSERT_EQ(got.type(), CV_8UC1);
      if (f == V4L2_PIX_FMT_MJPEG) {
        EXPECT_LT(mean_abs_diff(got, images[i]), 2.0);  // JPEG quality 95
        EXPECT_GT(mean_abs_diff(got, images[i]), 0.0);  // lossy: it really was decoded
      } else if (f == V4L2_PIX_FMT_Y16) {
        // High byte, rounded by the low one (< 0x80 here): exactly the picture.
        EXPECT_EQ(cv::norm(got, images[i], cv::NORM_INF), 0.0);
      } else {
        EXPECT_EQ(cv::norm(got, images[i], cv::NORM_INF), 0.0);
      }
    }
  }
  // 16-bit output keeps the full Y16 value; BGR output from YUYV is BT.601 video range.
  V4l2CameraConfig y16;
  y16.format = PixelFormat::kMono16;
  const RunResult r16 = run(recording(images, V4L2_PIX_FMT_Y16), y16);
  ASSERT_EQ(r16.frames.size(), 2u);
  EXPECT_EQ(r16.frames[0].image.at<std::uint16_t>(3, 5),
            (images[0].at<std::uint8_t>(3, 5) << 8) | ((3 * 7 + 5) & 0x7F));
  V4l2CameraConfig bgr;
  bgr.format = PixelFormat::kBgr8;
  const RunResult rb = run(recording(images, V4L2_PIX_FMT_YUYV), bgr);
  ASSERT_EQ(rb.frames.size(), 2u);
  const cv::Vec3b px = rb.frames[0].image.at<cv::Vec3b>(100, 200);
  const double y = images[0].at<std::uint8_t>(100, 200);
  const double expected = std::clamp(1.164 * (y - 16.0), 0.0, 255.0);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(px[c], expected, 1.5);
}

TEST(V4l2Recorded, FormatNegotiationPrefersLosslessFormatsAndExplainsFailures) {
  const auto images = euroc_frames();
  // Offered MJPG first and YUYV second: mono8 takes YUYV (lossless, no decoding).
  V4l2CameraConfig cfg;
  auto rec = recording(images, V4L2_PIX_FMT_YUYV, {V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_YUYV});
  EXPECT_EQ(run(rec, cfg).wire, WireFormat::kYuyv);
  // A configured preference wins.
  cfg.wire_formats = {WireFormat::kMjpeg, WireFormat::kYuyv};
  auto mj = recording(images, V4L2_PIX_FMT_MJPEG, {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_MJPEG});
  EXPECT_EQ(run(mj, cfg).wire, WireFormat::kMjpeg);

  auto open_error = [&](V4l2Recording r, V4l2CameraConfig c) -> std::string {
    auto dev = std::make_shared<RecordedV4l2Device>(r);
    if (c.path.empty()) c.path = r.path;
    if (c.width == 0) c.width = r.width;
    if (c.height == 0) c.height = r.height;
    V4l2Camera cam(c, dev);
    try {
      cam.open();
    } catch (const Error& e) {
      return e.what();
    }
    return "opened";
  };
  // 16-bit output from a device without Y16.
  V4l2CameraConfig mono16;
  mono16.format = PixelFormat::kMono16;
  const auto e1 = open_error(
      recording(images, V4L2_PIX_FMT_YUYV, {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_MJPEG}), mono16);
  EXPECT_NE(e1.find("offers none of the formats"), std::string::npos) << e1;
  EXPECT_NE(e1.find("YUYV, MJPG"), std::string::npos) << e1;
  // The device delivers another size than configured.
  V4l2CameraConfig big;
  big.width = 1280;
  big.height = 1024;
  const auto e2 = open_error(recording(images, V4L2_PIX_FMT_GREY), big);
  EXPECT_NE(e2.find("delivers 752x480 in GREY, not the configured 1280x1024"), std::string::npos)
      << e2;
  // A device that is not there.
  V4l2CameraConfig missing;
  missing.path = "/dev/video7";
  const auto e3 = open_error(recording(images, V4L2_PIX_FMT_GREY), missing);
  EXPECT_EQ(e3, "V4L2 device /dev/video7: does not exist") << e3;
  // A frame rate the device cannot set.
  auto fixed = recording(images, V4L2_PIX_FMT_GREY);
  fixed.timeperframe = false;
  V4l2CameraConfig rate;
  rate.frame_rate_hz = 30.0;
  const auto e4 = open_error(fixed, rate);
  EXPECT_NE(e4.find("cannot set the frame rate"), std::string::npos) << e4;
  // ... and one that can.
  auto dev = std::make_shared<RecordedV4l2Device>(recording(images, V4L2_PIX_FMT_GREY));
  rate.path = "/dev/video0";
  rate.width = 752;
  rate.height = 480;
  V4l2Camera cam(rate, dev);
  cam.open();
  EXPECT_NEAR(dev->frame_rate().value_or(0.0), 30.0, 1e-9);
}

TEST(V4l2Recorded, TimestampFlagsSequenceGapsAndErrorBuffers) {
  const auto images = euroc_frames();
  V4l2Recording rec = recording({images[0]}, V4L2_PIX_FMT_GREY);
  rec.exposure_100us = 80;  // 8 ms, read back at open
  const auto grey = encode(images[0], V4L2_PIX_FMT_GREY);
  const RealtimeToMonotonic realtime;
  const std::int64_t rt_stamp = host_now().ns + realtime.offset_ns();  // "now" on CLOCK_REALTIME
  rec.frames = {
      {grey, 10, 7'000'000'123'456, kMonoSoe},  // 7000.000123456 s: truncated to us
      {grey, 11, 7'000'050'000'000,
       V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_EOF},
      {grey, 14, 7'000'200'000'000, kMonoSoe},                        // 12 and 13 lost
      {grey, 15, 7'000'250'000'000, kMonoSoe | V4L2_BUF_FLAG_ERROR},  // corrupt: dropped
      {grey, 16, rt_stamp, V4L2_BUF_FLAG_TIMESTAMP_UNKNOWN},          // legacy wall clock
      {grey, 17, 123, V4L2_BUF_FLAG_TIMESTAMP_COPY},                  // m2m: no capture time
      {{grey.begin(), grey.begin() + 1000}, 18, 7'000'400'000'000, kMonoSoe},  // short
  };
  CameraClockConfig clock;
  clock.readout = std::chrono::milliseconds(3);
  clock.time_offset = std::chrono::microseconds(-500);
  const std::int64_t before = host_now().ns;
  const RunResult r = run(rec, {}, clock);
  const std::int64_t after = host_now().ns;
  ASSERT_EQ(r.frames.size(), 5u);
  EXPECT_EQ(r.counters.frames, 7u);
  EXPECT_EQ(r.counters.sequence_gaps, 2u);
  EXPECT_EQ(r.counters.incomplete, 1u);
  EXPECT_EQ(r.counters.convert_errors, 1u);
  constexpr std::int64_t kExp = 8'000'000;

  const CameraFrame& soe = r.frames[0];
  EXPECT_EQ(soe.info.sensor_time.ns, 7'000'000'123'000);
  EXPECT_EQ(soe.info.instant, StampInstant::kStartOfExposure);
  EXPECT_EQ(soe.info.clock, CameraClockKind::kHostMonotonic);
  EXPECT_EQ(soe.info.exposure.count(), kExp);
  EXPECT_EQ(soe.info.exposure_source, ExposureSource::kReadback);
  EXPECT_EQ(soe.info.sequence, 10u);
  // Host-monotonic stamps map directly: start of exposure + offset, mid = + exposure / 2.
  EXPECT_EQ(soe.exposure_start.ns, 7'000'000'123'000 - 500'000);
  EXPECT_EQ(soe.mid_exposure.ns, 7'000'000'123'000 - 500'000 + kExp / 2);
  EXPECT_GE(soe.info.host_rx.ns, before);
  EXPECT_LE(soe.info.host_rx.ns, after);

  const CameraFrame& eof = r.frames[1];
  EXPECT_EQ(eof.info.instant, StampInstant::kEndOfFrame);
  // End of frame: exposure started readout + exposure before the stamp.
  EXPECT_EQ(eof.exposure_start.ns, 7'000'050'000'000 - 3'000'000 - kExp - 500'000);
  EXPECT_EQ(eof.mid_exposure.ns, eof.exposure_start.ns + kExp / 2);
  EXPECT_EQ(eof.stamp.mapped.ns, 7'000'050'000'000 - 500'000);

  EXPECT_EQ(r.frames[2].info.sequence, 14u);
  // UNKNOWN clock: converted from CLOCK_REALTIME to CLOCK_MONOTONIC at capture.
  EXPECT_NEAR(static_cast<double>(r.frames[3].info.sensor_time.ns),
              static_cast<double>(rt_stamp - realtime.offset_ns()), 2e6);
  // COPY: the dequeue time stands in.
  EXPECT_EQ(r.frames[4].info.sensor_time.ns, r.frames[4].info.host_rx.ns);
  EXPECT_EQ(r.frames[4].info.instant, StampInstant::kEndOfFrame);
}

TEST(V4l2Recorded, ExposureIsSetReadBackAndChangedWhileStreaming) {
  const auto images = euroc_frames();
  auto rec = recording({images[0], images[1], images[0], images[1]}, V4L2_PIX_FMT_GREY);
  auto dev = std::make_shared<RecordedV4l2Device>(rec);
  V4l2CameraConfig cfg;
  cfg.path = rec.path;
  cfg.width = rec.width;
  cfg.height = rec.height;
  cfg.exposure = std::chrono::microseconds(4960);  // 49.6 units: rounds to 50 = 5 ms
  cfg.gain = 12.0;
  V4l2Camera cam(cfg, dev);
  cam.open();
  EXPECT_FALSE(dev->auto_exposure());
  EXPECT_EQ(dev->exposure_100us(), 50);
  TestSink sink(cfg.width, cfg.height, cfg.format);
  CameraClock clock({});
  ASSERT_EQ(cam.next_frame(std::chrono::milliseconds(1), sink), CameraBackend::Result::kFrame);
  auto f0 = sink.take(clock);
  ASSERT_TRUE(f0);
  EXPECT_EQ(f0->info.exposure, std::chrono::milliseconds(5));
  EXPECT_EQ(f0->info.gain, 12.0);
  // A change requested from another thread is applied between frames and read back.
  cam.request({.exposure = std::chrono::microseconds(2000)});
  EXPECT_TRUE(cam.service());
  EXPECT_EQ(dev->exposure_100us(), 20);
  ASSERT_EQ(cam.next_frame(std::chrono::milliseconds(1), sink), CameraBackend::Result::kFrame);
  auto f1 = sink.take(clock);
  ASSERT_TRUE(f1);
  EXPECT_EQ(f1->info.exposure, std::chrono::milliseconds(2));
  EXPECT_EQ(cam.counters().exposure_ns, 2'000'000);
  // A camera without exposure controls cannot honour a configured exposure: open fails.
  rec.exposure_controls = false;
  auto dev2 = std::make_shared<RecordedV4l2Device>(rec);
  V4l2Camera cam2(cfg, dev2);
  EXPECT_THROW(cam2.open(), Error);
}

}  // namespace
}  // namespace livod::camera

namespace livod::camera {
namespace {

TEST(V4l2Recorded, CorruptOrWrongSizeMjpegFramesAreCountedNotDecoded) {
  const auto images = euroc_frames();
  auto rec = recording(images, V4L2_PIX_FMT_MJPEG);
  cv::Mat big;
  cv::resize(images[0], big, {images[0].cols * 2, images[0].rows * 2});
  std::vector<std::uint8_t> big_jpeg;
  cv::imencode(".jpg", big, big_jpeg);
  auto garbage = rec.frames[0].bytes;
  for (std::size_t i = 200; i < garbage.size(); i += 7) garbage[i] ^= 0x5A;
  rec.frames.push_back({big_jpeg, 2, 5'100'000'000, kMonoSoe});                        // size
  rec.frames.push_back({{0xFF, 0xD8, 0xFF, 0xC0, 0x00}, 3, 5'150'000'000, kMonoSoe});  // truncated
  rec.frames.push_back({garbage, 4, 5'200'000'000, kMonoSoe});                         // corrupt
  const RunResult r = run(rec, {});
  EXPECT_EQ(r.counters.frames, 5u);
  // The two good frames; the one twice the size and the truncated one are refused before
  // decoding. libjpeg decodes a corrupted scan with artefacts rather than failing.
  EXPECT_GE(r.counters.convert_errors, 2u);
  EXPECT_EQ(r.frames.size() + r.counters.convert_errors, 5u);
}

}  // namespace
}  // namespace livod::camera

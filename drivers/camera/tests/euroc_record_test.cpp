// Camera frames recorded as an EuRoC folder replay losslessly: frames captured from recorded V4L2
// buffers (real EuRoC images) through a CameraSource, written with EurocCameraWriter at their
// mid-exposure time, read back with the EuRoC reader: identical pixels, stamps and exposures.

#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <chrono>
#include <opencv2/core.hpp>
#include <thread>

#include "drivers/camera/camera_source.hpp"
#include "drivers/camera/v4l2_camera.hpp"
#include "drivers/camera/v4l2_recorded.hpp"
#include "io/euroc.hpp"
#include "io/euroc_image.hpp"
#include "io/euroc_writer.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::camera {
namespace {

using namespace std::chrono_literals;

TEST(EurocRecord, CapturedFramesReplayLosslesslyFromTheFolder) {
  const auto records = io::read_euroc_camera_csv(test::data_path("euroc_v101/mav0/cam0/data.csv"));
  ASSERT_GE(records.size(), 8u);
  V4l2Recording rec;
  rec.formats = {V4L2_PIX_FMT_GREY};
  std::vector<cv::Mat> originals;
  for (std::size_t i = 0; i < 8; ++i) {
    const cv::Mat img = io::load_euroc_image(records[i], io::ImageDecodeMode::kMono8);
    originals.push_back(img);
    rec.width = img.cols;
    rec.height = img.rows;
    rec.frames.push_back({{img.data, img.data + img.total()},
                          static_cast<std::uint32_t>(i),
                          records[i].timestamp.ns,
                          V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_SOE});
  }
  rec.exposure_100us = 37;  // 3.7 ms
  rec.pace = 1ms;
  auto dev = std::make_shared<RecordedV4l2Device>(rec);
  V4l2CameraConfig vc;
  vc.path = rec.path;
  vc.width = rec.width;
  vc.height = rec.height;
  CameraSourceConfig sc;
  sc.name = "cam0";
  sc.width = rec.width;
  sc.height = rec.height;
  sc.thread.poll_timeout = 5ms;
  CameraSource source(sc, std::make_unique<V4l2Camera>(vc, dev));

  const auto folder = test::temp_dir("euroc_record") / "mav0" / "cam0";
  io::EurocCameraWriter writer(folder);
  std::vector<std::int64_t> stamps;
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (writer.frames() < 8 && std::chrono::steady_clock::now() < deadline) {
    source.poll([&](const CameraFrame& f) {
      writer.write(SensorTime(f.mid_exposure.ns), f.image, f.info.exposure);
      stamps.push_back(f.mid_exposure.ns);
    });
    std::this_thread::sleep_for(2ms);
  }
  writer.flush();
  ASSERT_EQ(writer.frames(), 8u);

  const io::EurocFolder back(folder.parent_path().parent_path());
  const auto got = back.images("cam0");
  ASSERT_EQ(got.size(), 8u);
  for (std::size_t i = 0; i < got.size(); ++i) {
    // Mid-exposure of a start-of-exposure stamp (microsecond resolution on the V4L2 wire).
    EXPECT_EQ(got[i].timestamp.ns, records[i].timestamp.ns / 1000 * 1000 + 1'850'000);
    EXPECT_EQ(got[i].timestamp.ns, stamps[i]);
    ASSERT_TRUE(got[i].exposure);
    EXPECT_EQ(*got[i].exposure, 3700us);
    const cv::Mat img = io::load_euroc_image(got[i]);
    EXPECT_EQ(cv::norm(img, originals[i], cv::NORM_INF), 0.0) << i;
  }
  // Timestamps must increase.
  EXPECT_THROW(writer.write(SensorTime(stamps.back()), originals[0], std::nullopt),
               std::invalid_argument);
}

}  // namespace
}  // namespace livod::camera

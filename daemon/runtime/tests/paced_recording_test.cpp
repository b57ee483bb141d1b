// A paced recording (`replay --realtime`) moves every receive time it delivers onto the schedule:
// scans, IMU samples and camera frames alike. A frame left on the recording's clock would reach
// the camera's clock domain hours away from the LiDAR and never meet an image group.

#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "core/image.hpp"
#include "daemon/runtime/paced_sources.hpp"

namespace livod::daemon::runtime {
namespace {

// One event at record time 1000 s carrying a scan, an IMU sample and a camera frame.
class OneEventRecording final : public MeasurementSource {
 public:
  std::optional<std::int64_t> peek_time() override {
    if (delivered_) return std::nullopt;
    return kRecordNs;
  }
  void deliver(const drivers::DecoderSinks& sinks) override {
    delivered_ = true;
    LidarScan scan;
    scan.start.host = HostTime(kRecordNs);
    sinks.on_scan(scan);
    ImuSample imu;
    imu.stamp.host = HostTime(kRecordNs);
    sinks.on_imu(imu);
    ImageFrame frame;
    frame.stamp.host = HostTime(kRecordNs);
    frame.image = cv::Mat(4, 4, CV_8UC1, cv::Scalar(7));
    sinks.on_image(frame);
  }
  void finish(const drivers::DecoderSinks& /*sinks*/) override {}
  [[nodiscard]] std::string summary() const override { return "one event"; }

  static constexpr std::int64_t kRecordNs = 1'000'000'000'000;

 private:
  bool delivered_ = false;
};

TEST(PacedRecording, MovesScansImuAndImagesOntoTheSchedule) {
  PaceSchedule schedule;
  schedule.t0_record_ns = OneEventRecording::kRecordNs;
  schedule.start = HostTime(host_now().ns - 5'000'000'000);  // started 5 s ago: the event is due
  auto paced = pace_recording(std::make_unique<OneEventRecording>(), schedule);

  const auto due = paced->peek_time();
  ASSERT_TRUE(due.has_value());
  EXPECT_EQ(*due, schedule.start.ns);

  std::vector<std::int64_t> scan_host, imu_host, image_host;
  cv::Mat pixels;
  drivers::DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& s) { scan_host.push_back(s.start.host.ns); };
  sinks.on_imu = [&](const ImuSample& s) { imu_host.push_back(s.stamp.host.ns); };
  sinks.on_image = [&](const ImageFrame& f) {
    image_host.push_back(f.stamp.host.ns);
    pixels = f.image;
  };
  paced->deliver(sinks);

  const std::vector<std::int64_t> expected{schedule.start.ns};
  EXPECT_EQ(scan_host, expected);
  EXPECT_EQ(imu_host, expected);
  EXPECT_EQ(image_host, expected);
  ASSERT_FALSE(pixels.empty());
  EXPECT_EQ(pixels.at<std::uint8_t>(2, 2), 7);
  EXPECT_TRUE(paced->exhausted());
}

}  // namespace
}  // namespace livod::daemon::runtime

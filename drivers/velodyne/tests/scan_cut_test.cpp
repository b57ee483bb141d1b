// Frame cut modes on the real VLP-16 capture (20 Hz, 52 VeloView frames).

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "drivers/velodyne/tests/capture.hpp"
#include "drivers/velodyne/velodyne_decoder.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers::velodyne {
namespace {

const char* const kVlp16 = "velodyne/veloview/vlp-16-test-90deg-1-50-frames.pcap";

capture::Decoded decode(ScanCut cut, double angle_deg, std::int64_t period_ns) {
  VelodyneOptions options;
  options.model = Model::kVlp16;
  options.cut = cut;
  options.cut_angle_deg = angle_deg;
  options.cut_period_ns = period_ns;
  VelodyneDecoder decoder(options);
  auto decoded = capture::decode_capture(livod::test::data_path(kVlp16), decoder);
  EXPECT_EQ(decoder.counters().scans, decoded.scans.size());
  // Only the first and the last scans are partial turns.
  EXPECT_EQ(decoder.counters().incomplete_scans, 2U);
  return decoded;
}

std::size_t total_points(const capture::Decoded& d) {
  std::size_t n = 0;
  for (const auto& s : d.scans) n += s.size();
  return n;
}

double azimuth_deg(const LidarScan& s, std::size_t i) {
  const double a = std::atan2(-static_cast<double>(s.y[i]), s.x[i]) * 180.0 / std::numbers::pi;
  return a < 0 ? a + 360.0 : a;
}

TEST(ScanCut, EveryModeKeepsEveryPoint) {
  const auto by_decrease = decode(ScanCut::kAzimuthDecrease, 0, 0);
  const auto by_angle = decode(ScanCut::kAzimuthAngle, 180.0, 0);
  const auto by_time = decode(ScanCut::kTimePeriod, 0, 50'000'000);
  EXPECT_EQ(by_decrease.scans.size(), 52U);
  EXPECT_EQ(total_points(by_angle), total_points(by_decrease));
  EXPECT_EQ(total_points(by_time), total_points(by_decrease));
}

TEST(ScanCut, AngleCutStartsEveryScanAtTheCutAngle) {
  const auto decoded = decode(ScanCut::kAzimuthAngle, 180.0, 0);
  ASSERT_GE(decoded.scans.size(), 50U);
  ASSERT_LE(decoded.scans.size(), 53U);
  for (std::size_t k = 1; k < decoded.scans.size(); ++k) {
    const LidarScan& s = decoded.scans[k];
    // The first block at or after 180 degrees: its first returns lie within one block (< 0.5
    // degree at 20 Hz) after the cut angle.
    EXPECT_GE(azimuth_deg(s, 0), 180.0 - 0.01) << "scan " << k;
    EXPECT_LT(azimuth_deg(s, 0), 180.9) << "scan " << k;
  }
  for (std::size_t k = 1; k + 1 < decoded.scans.size(); ++k) {
    EXPECT_NEAR(decoded.scans[k].t_offset_ns.back(), 50e6, 1.5e6) << "scan " << k;  // 20 Hz
  }
}

TEST(ScanCut, TimeCutAlignsScansToThePeriodGrid) {
  constexpr std::int64_t kPeriod = 25'000'000;
  const auto decoded = decode(ScanCut::kTimePeriod, 0, kPeriod);
  ASSERT_GT(decoded.scans.size(), 100U);
  for (std::size_t k = 0; k < decoded.scans.size(); ++k) {
    const LidarScan& s = decoded.scans[k];
    const std::int64_t start = s.start.sensor.ns;
    const std::int64_t end = start + s.t_offset_ns.back();
    // Block granularity: a scan may reach into the next period by less than one block.
    EXPECT_LT(end - (start / kPeriod) * kPeriod, kPeriod + 111'000) << "scan " << k;
    if (k > 0) {
      const std::int64_t previous = decoded.scans[k - 1].start.sensor.ns;
      EXPECT_EQ(start / kPeriod, previous / kPeriod + 1) << "scan " << k;
    }
  }
}

}  // namespace
}  // namespace livod::drivers::velodyne

// Reproduces VeloView's published expectations (Kitware/VeloView Testing/*.test) on the real
// HDL-32E "monterey" and VLP-16 captures. The .test files are read as VeloView's TestReader
// reads them: `frame_count N`, `frame K`, `point_count N`,
// `point_values id x y z intensity is_dual [dual_distance dual_intensity]`, compared to 1e-4.
//
// VeloView's frame: y forward, x = r cos(w) sin(a), y = r cos(w) cos(a) -> (x_vv, y_vv, z) =
// (-y, x, z) of livod's x-forward frame. VeloView starts the first frame at the first packet and
// cuts when a block azimuth decreases (ScanCut::kAzimuthDecrease), drops zero ranges and rounds
// its interpolated azimuths to 0.01 degree (AzimuthInterpolation::kVeloView).

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "drivers/velodyne/tests/capture.hpp"
#include "drivers/velodyne/velodyne_decoder.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers::velodyne {
namespace {

struct ExpectedPoint {
  std::size_t index;
  double x, y, z;  // VeloView frame
  int intensity;
};

struct ExpectedFrame {
  std::size_t frame;
  std::optional<std::size_t> point_count;
  std::vector<ExpectedPoint> points;
};

struct Expectations {
  std::size_t frame_count = 0;
  std::vector<ExpectedFrame> frames;
};

Expectations read_test_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  Expectations e;
  std::string command;
  while (in >> command) {
    if (command == "frame_count") {
      in >> e.frame_count;
    } else if (command == "frame") {
      ExpectedFrame f;
      in >> f.frame;
      e.frames.push_back(f);
    } else if (command == "point_count") {
      std::size_t n = 0;
      in >> n;
      e.frames.back().point_count = n;
    } else if (command == "point_values") {
      ExpectedPoint p{};
      int is_dual = 0;
      in >> p.index >> p.x >> p.y >> p.z >> p.intensity >> is_dual;
      if (is_dual != 0) {
        int relative_distance = 0;
        int relative_intensity = 0;
        in >> relative_distance >> relative_intensity;
      }
      e.frames.back().points.push_back(p);
    } else {
      ADD_FAILURE() << "unknown command in " << path << ": " << command;
      break;
    }
    if (!in) {
      ADD_FAILURE() << "truncated command " << command << " in " << path;
    }
  }
  return e;
}

VelodyneOptions veloview_options(Model model, const std::string& xml,
                                 AzimuthInterpolation azimuth) {
  VelodyneOptions options;
  options.model = model;
  options.calibration_file = livod::test::data_path(xml);
  options.decode.azimuth = azimuth;
  options.cut = ScanCut::kAzimuthDecrease;
  return options;
}

// Checks every expectation; `tolerance_for` gives the allowed position error of a point.
template <class Tolerance>
void check_against(const capture::Decoded& decoded, const Expectations& expected,
                   Tolerance tolerance_for) {
  ASSERT_EQ(decoded.scans.size(), expected.frame_count);
  for (std::size_t i = 0; i < decoded.scans.size(); ++i) {
    EXPECT_EQ(decoded.scans[i].sequence, i);
  }
  std::size_t checked_points = 0;
  for (const auto& frame : expected.frames) {
    ASSERT_LT(frame.frame, decoded.scans.size());
    const LidarScan& scan = decoded.scans[frame.frame];
    if (frame.point_count) {
      EXPECT_EQ(scan.size(), *frame.point_count) << "frame " << frame.frame;
    }
    for (const auto& p : frame.points) {
      ASSERT_LT(p.index, scan.size());
      const double x_vv = -scan.y[p.index];
      const double y_vv = scan.x[p.index];
      const double z_vv = scan.z[p.index];
      const double tolerance = tolerance_for(p);
      EXPECT_NEAR(x_vv, p.x, tolerance) << "frame " << frame.frame << " point " << p.index;
      EXPECT_NEAR(y_vv, p.y, tolerance) << "frame " << frame.frame << " point " << p.index;
      EXPECT_NEAR(z_vv, p.z, 1e-4) << "frame " << frame.frame << " point " << p.index;
      EXPECT_EQ(scan.intensity[p.index], p.intensity);
      ++checked_points;
    }
  }
  EXPECT_GT(checked_points, 0U);
}

struct Case {
  const char* capture;
  const char* expectations;
  const char* calibration;
  Model model;
};

class VeloViewReference : public ::testing::TestWithParam<Case> {};

TEST_P(VeloViewReference, MatchesVeloViewToTenthOfAMillimetre) {
  const Case& c = GetParam();
  VelodyneDecoder decoder(
      veloview_options(c.model, c.calibration, AzimuthInterpolation::kVeloView));
  const auto decoded = capture::decode_capture(livod::test::data_path(c.capture), decoder);
  check_against(decoded, read_test_file(livod::test::data_path(c.expectations)),
                [](const ExpectedPoint&) { return 1e-4; });
  EXPECT_EQ(decoder.counters().decode_errors, 0U);
  EXPECT_EQ(decoder.counters().sequence_gaps, 0U);
}

// The default interpolation differs from VeloView only by VeloView's rounding of the azimuth to
// 0.01 degree (and its median rate): the horizontal error is bounded by r * 0.011 degree.
TEST_P(VeloViewReference, DefaultInterpolationWithinVeloViewsAzimuthQuantisation) {
  const Case& c = GetParam();
  VelodyneDecoder decoder(
      veloview_options(c.model, c.calibration, AzimuthInterpolation::kPacketRate));
  const auto decoded = capture::decode_capture(livod::test::data_path(c.capture), decoder);
  constexpr double kQuantisationRad = 0.011 * std::numbers::pi / 180.0;
  check_against(
      decoded, read_test_file(livod::test::data_path(c.expectations)),
      [](const ExpectedPoint& p) { return 1e-4 + std::hypot(p.x, p.y) * kQuantisationRad; });
}

INSTANTIATE_TEST_SUITE_P(
    Captures, VeloViewReference,
    ::testing::Values(Case{"velodyne/veloview/monterey-first-100-packets.pcap",
                           "velodyne/veloview/monterey.test", "velodyne/veloview/HDL-32.xml",
                           Model::kHdl32e},
                      // Early VLP-16 firmware: the factory byte says HDL-32E; the configured
                      // model wins.
                      Case{"velodyne/veloview/vlp-16-test-90deg-1-50-frames.pcap",
                           "velodyne/veloview/vlp-16.test", "velodyne/veloview/VLP-16.xml",
                           Model::kVlp16}),
    [](const ::testing::TestParamInfo<Case>& param_info) {
      return param_info.param.model == Model::kHdl32e ? std::string("Hdl32eMonterey")
                                                      : std::string("Vlp16");
    });

TEST(VeloViewReference, FactoryByteMismatchIsCountedNotFatal) {
  VelodyneDecoder decoder(veloview_options(Model::kVlp16, "velodyne/veloview/VLP-16.xml",
                                           AzimuthInterpolation::kPacketRate));
  const auto decoded = capture::decode_capture(
      livod::test::data_path("velodyne/veloview/vlp-16-test-90deg-1-50-frames.pcap"), decoder);
  EXPECT_EQ(decoder.counters().lidar_packets, 1902U);
  EXPECT_EQ(decoder.velodyne_counters().factory_byte_mismatches, 1902U);
  EXPECT_EQ(decoded.scans.size(), 52U);
  // Every ring of the VLP-16 shows up, and rings follow elevation (z / range = sin(w)).
  std::vector<double> elevation_sum(16, 0.0);
  std::vector<int> elevation_count(16, 0);
  for (const auto& scan : decoded.scans) {
    for (std::size_t i = 0; i < scan.size(); ++i) {
      const double r =
          std::sqrt(scan.x[i] * scan.x[i] + scan.y[i] * scan.y[i] + scan.z[i] * scan.z[i]);
      elevation_sum[scan.ring[i]] += std::asin(scan.z[i] / r);
      ++elevation_count[scan.ring[i]];
    }
  }
  for (int ring = 0; ring < 16; ++ring) {
    ASSERT_GT(elevation_count[static_cast<std::size_t>(ring)], 0) << "ring " << ring;
    const double mean_deg = elevation_sum[static_cast<std::size_t>(ring)] /
                            elevation_count[static_cast<std::size_t>(ring)] * 180.0 /
                            std::numbers::pi;
    EXPECT_NEAR(mean_deg, -15.0 + 2.0 * ring, 1e-3) << "ring " << ring;
  }
}

TEST(VeloViewReference, HdlTimestampsAreContinuousAndOnTheCaptureHour) {
  VelodyneDecoder decoder(veloview_options(Model::kHdl32e, "velodyne/veloview/HDL-32.xml",
                                           AzimuthInterpolation::kPacketRate));
  const auto decoded = capture::decode_capture(
      livod::test::data_path("velodyne/veloview/monterey-first-100-packets.pcap"), decoder);
  ASSERT_EQ(decoded.scans.size(), 19U);
  // The capture starts at 2012-12-11 22:06:34 UTC (pcap time) and the sensor's clock is on GPS
  // time: the scans must land within a second of the record times.
  constexpr std::int64_t kCaptureStartNs = 1'355'263'594'123'168'000;
  EXPECT_NEAR(static_cast<double>(decoded.scans.front().start.sensor.ns - kCaptureStartNs), 0.0,
              1e9);
  EXPECT_NEAR(static_cast<double>(decoded.scans.front().start.host.ns - kCaptureStartNs), 0.0, 1e6);
  for (std::size_t i = 0; i < decoded.scans.size(); ++i) {
    const LidarScan& scan = decoded.scans[i];
    ASSERT_FALSE(scan.empty());
    EXPECT_EQ(scan.t_offset_ns.front(), 0);
    // Within a scan time never goes backwards by more than a firing (point order is firing
    // order), and a 10 Hz scan lasts < 0.11 s.
    for (std::size_t k = 1; k < scan.size(); ++k) {
      ASSERT_GE(scan.t_offset_ns[k], scan.t_offset_ns[k - 1]) << "scan " << i << " point " << k;
    }
    EXPECT_LT(scan.t_offset_ns.back(), 110'000'000);
    if (i > 0) {
      const LidarScan& previous = decoded.scans[i - 1];
      const std::int64_t previous_end = previous.start.sensor.ns + previous.t_offset_ns.back();
      EXPECT_GT(scan.start.sensor.ns, previous_end);
      EXPECT_LT(scan.start.sensor.ns - previous_end, 1'000'000);  // < 1 ms between scans
    }
  }
}

}  // namespace
}  // namespace livod::drivers::velodyne

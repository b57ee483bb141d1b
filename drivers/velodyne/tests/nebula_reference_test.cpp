// VLP-16 dual-return capture against nebula's decoded reference cloud
// (tier4/nebula test_resources/decoder_ground_truth/vlp16, shared/data/velodyne/nebula_vlp16).
//
// Settings from VLP16.param.yaml: calibration VLP16.yaml, return mode Dual, min_range 0.3 m,
// max_range 300 m, scan_phase 0, cloud angles 0..360 (no crop).
//
// Aligning the scans: the capture holds four packet messages of about one turn each (603
// packets; the block azimuth crosses 0 degrees in packets 150, 301, 452 and 602). nebula
// finishes a cloud per message and moves the points at the end of a message that already lie
// past the scan phase (0 degrees) into an overflow buffer for the next cloud. The reference
// cloud 1673400472138016708.pcd, completed by the 4th message, is therefore exactly one turn:
// from packet 452 block 0 (0.30 degrees) to packet 602 block 7 (359.85 degrees); packet 602's
// blocks 8..11 (0.23..0.63 degrees) went to the overflow. livod's azimuth-decrease cut
// produces that turn as its 4th scan (index 3): before it come the partial turn up to the
// first crossing and two full turns, after it the 0.23..0.63 degree tail. The test checks the
// alignment by comparing the point sets one to one, in order (same count, same values).
//
// Tolerances: ranges, heights, horizontal radii (float rounding), intensities, rings and the
// dual-return classification agree exactly; azimuths within the bounds explained at
// kAzimuthBounds below (nebula's rounding to 0.01 degree and its per-block azimuth rule).
//
// Not compared: nebula's time_stamp field. It is built with the single-return firing table
// even in dual mode (block pair k at 2k x 110.592 us instead of k x 110.592 us) and the
// packet stamps it starts from are quantised by a double at 1.7e9 s; the dual-return timing is
// checked against the firing table in firing_timing_test instead.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "drivers/velodyne/tests/capture.hpp"
#include "drivers/velodyne/velodyne_decoder.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers::velodyne {
namespace {

double azimuth_deg(const LidarScan& scan, std::size_t i) {
  const double a =
      std::atan2(-static_cast<double>(scan.y[i]), scan.x[i]) * 180.0 / std::numbers::pi;
  return a < 0.0 ? a + 360.0 : a;
}

// Which points of livod's scan nebula's cloud holds:
// * nebula's test node declares cloud_max_angle with a default of 359 degrees (the 360 of
//   VLP16.param.yaml is not read by the test): a point whose azimuth, rounded to 0.01 degree,
//   exceeds 359.00 degrees is dropped;
// * livod cuts scans at block boundaries, so the second firing sequence of the last block
//   (359.85 degrees) interpolates past 360 degrees into the scan's tail; nebula moves such
//   trailing points (azimuth below 2 degrees at the end of its cloud) to the next cloud.
std::vector<bool> nebula_crop(const LidarScan& scan) {
  std::vector<bool> keep(scan.size());
  for (std::size_t i = 0; i < scan.size(); ++i) {
    keep[i] = std::lround(azimuth_deg(scan, i) * 100.0) <= 35900;
  }
  for (std::size_t i = scan.size(); i > 0 && azimuth_deg(scan, i - 1) < 2.0; --i) {
    keep[i - 1] = false;
  }
  return keep;
}

struct NebulaPoint {
  float x, y, z;
  std::uint8_t intensity;
  std::uint8_t return_type;
  std::uint16_t channel;
  float azimuth, elevation, distance;
  std::uint32_t time_stamp;
};

// nebula ReturnType values (nebula_common.hpp).
constexpr std::uint8_t kFirstWeak = 4;
constexpr std::uint8_t kLastWeak = 5;
constexpr std::uint8_t kIdentical = 6;
constexpr std::uint8_t kFirstStrongest = 9;
constexpr std::uint8_t kLastStrongest = 10;

std::vector<NebulaPoint> read_nebula_pcd(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  std::size_t points = 0;
  while (std::getline(in, line)) {
    if (line.rfind("FIELDS", 0) == 0) {
      EXPECT_EQ(line,
                "FIELDS x y z intensity return_type channel azimuth elevation distance time_stamp");
    }
    if (line.rfind("POINTS", 0) == 0) points = std::stoul(line.substr(7));
    if (line.rfind("DATA", 0) == 0) {
      EXPECT_EQ(line, "DATA binary");
      break;
    }
  }
  constexpr std::size_t kRecord = 32;  // SIZE 4 4 4 1 1 2 4 4 4 4
  std::vector<char> bytes(points * kRecord);
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  EXPECT_EQ(static_cast<std::size_t>(in.gcount()), bytes.size());
  std::vector<NebulaPoint> out(points);
  for (std::size_t i = 0; i < points; ++i) {
    const char* r = bytes.data() + i * kRecord;
    NebulaPoint& p = out[i];
    std::memcpy(&p.x, r + 0, 4);
    std::memcpy(&p.y, r + 4, 4);
    std::memcpy(&p.z, r + 8, 4);
    std::memcpy(&p.intensity, r + 12, 1);
    std::memcpy(&p.return_type, r + 13, 1);
    std::memcpy(&p.channel, r + 14, 2);
    std::memcpy(&p.azimuth, r + 16, 4);
    std::memcpy(&p.elevation, r + 20, 4);
    std::memcpy(&p.distance, r + 24, 4);
    std::memcpy(&p.time_stamp, r + 28, 4);
  }
  return out;
}

// Azimuth agreement, livod minus nebula, in degrees. nebula computes a dual-return packet's
// azimuths block by block (vlp16_decoder.cpp unpack):
// * even blocks 0..8: block azimuth + (next pair's azimuth - this one) x firing fraction,
//   rounded to 0.01 degree. livod uses the packet's mean rate instead of the next pair's integer
//   difference; block azimuths jitter by +-1 count, so the two agree to 0.005 (rounding) +
//   0.02 (rate) degree.
// * odd blocks 1..9: nebula carries `azimuth_next` over from the even block, i.e. uses the NEXT
//   pair's block azimuth, and an interpolation span of 0 (that pair's two equal azimuths). livod
//   interpolates from the block's own azimuth, so it trails by one pair's rotation (0.40 degree
//   at 600 rpm) minus the firing's share of it.
// * blocks 10 and 11: nebula's span is 0 (the last pair has no next one): no interpolation.
//   livod leads by the firing's share of the rotation (up to 0.8 x 0.40 degree).
struct AzimuthBound {
  double min_deg;
  double max_deg;
};
constexpr std::array<AzimuthBound, 3> kAzimuthBounds{{
    {-0.025, 0.025},  // even blocks 0..8: interpolated by both
    {-0.41, -0.05},   // odd blocks 1..9: nebula uses the next pair's azimuth
    {-0.005, 0.33},   // blocks 10, 11: nebula does not interpolate
}};

class NebulaReference : public ::testing::Test {
 protected:
  void SetUp() override {
    VelodyneOptions options;
    options.model = Model::kVlp16;
    options.calibration_file = livod::test::data_path("velodyne/nebula_vlp16/VLP16.yaml");
    options.decode.min_range_m = 0.3;
    options.decode.max_range_m = 300.0;
    decoder_ = std::make_unique<VelodyneDecoder>(options);
    decoded_ = capture::decode_capture(
        livod::test::data_path("velodyne/nebula_vlp16/velodyne_vlp16.pcap"), *decoder_);
    reference_ =
        read_nebula_pcd(livod::test::data_path("velodyne/nebula_vlp16/1673400472138016708.pcd"));

    // The block each point of scan 3 came from: the scan starts with packet 452's block 0 and
    // lists returns in packet order, so the pure decoder's output from packet 452 on lines up.
    const DataPacketDecoder packet_decoder(
        Model::kVlp16, load_calibration(*options.calibration_file), options.decode);
    io::PcapReader reader(livod::test::data_path("velodyne/nebula_vlp16/velodyne_vlp16.pcap"));
    std::vector<DecodedReturn> returns(DataPacketDecoder::kMaxReturns);
    std::size_t packet = 0;
    while (auto datagram = reader.next()) {
      if (packet++ < kFirstPacketOfScan) continue;
      const auto r = packet_decoder.decode(datagram->payload, 0.0, returns);
      for (std::size_t i = 0; i < r.count; ++i) blocks_.push_back(returns[i].block);
    }
  }

  static constexpr std::size_t kFirstPacketOfScan = 452;
  std::vector<std::uint8_t> blocks_;

  std::unique_ptr<VelodyneDecoder> decoder_;
  capture::Decoded decoded_;
  std::vector<NebulaPoint> reference_;
};

TEST_F(NebulaReference, FourthScanIsNebulasCloudPointForPoint) {
  ASSERT_EQ(reference_.size(), 14831U);
  ASSERT_EQ(decoded_.scans.size(), 5U);  // partial turn, 3 turns, the wrapped tail
  const LidarScan& scan = decoded_.scans[3];
  const std::vector<bool> keep = nebula_crop(scan);
  ASSERT_EQ(static_cast<std::size_t>(std::count(keep.begin(), keep.end(), true)),
            reference_.size());
  EXPECT_EQ(scan.size() - reference_.size(), 48U);  // 40 above 359 degrees, 8 past 360

  std::array<std::size_t, 3> checked{};
  std::size_t strongest_agree = 0;
  std::size_t pairs = 0;
  std::size_t j = 0;  // index in the reference cloud
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!keep[i]) continue;
    const NebulaPoint& ref = reference_[j++];
    const double range = std::sqrt(static_cast<double>(scan.x[i]) * scan.x[i] +
                                   static_cast<double>(scan.y[i]) * scan.y[i] +
                                   static_cast<double>(scan.z[i]) * scan.z[i]);
    ASSERT_NEAR(range, ref.distance, 2e-6 * ref.distance + 1e-6) << "point " << i;
    // Range, height and horizontal radius do not depend on the azimuth: exact up to float.
    ASSERT_NEAR(scan.z[i], ref.z, 2e-6 * range) << "point " << i;
    ASSERT_NEAR(std::hypot(scan.x[i], scan.y[i]), std::hypot(ref.x, ref.y), 2e-6 * range + 1e-6)
        << "point " << i;
    // Azimuth (degrees, livod minus nebula): see kAzimuthBounds.
    double difference = (std::atan2(-static_cast<double>(scan.y[i]), scan.x[i]) -
                         std::atan2(-static_cast<double>(ref.y), ref.x)) *
                        180.0 / std::numbers::pi;
    if (difference > 180.0) difference -= 360.0;
    if (difference < -180.0) difference += 360.0;
    const int block = blocks_[i];
    const std::size_t rule = (block % 2 == 0 && block <= 8)   ? 0
                             : (block % 2 == 1 && block < 11) ? 1
                                                              : 2;
    const AzimuthBound& bound = kAzimuthBounds[rule];
    ASSERT_GE(difference, bound.min_deg) << "point " << i << " block " << block;
    ASSERT_LE(difference, bound.max_deg) << "point " << i << " block " << block;
    ++checked[rule];
    ASSERT_EQ(scan.intensity[i], ref.intensity) << "point " << i;
    ASSERT_EQ(scan.ring[i], ref.channel) << "point " << i;
    // Dual-return classification: nebula marks the lone return of a firing IDENTICAL; of a
    // pair, the stronger one (ties: the nearer one) is *_STRONGEST.
    switch (ref.return_type) {
      case kIdentical:
        EXPECT_EQ(scan.return_index[i], 0) << "point " << i;
        break;
      case kFirstStrongest:
      case kLastStrongest:
        EXPECT_EQ(scan.return_index[i], 0) << "point " << i;
        ++pairs;
        strongest_agree += scan.return_index[i] == 0 ? 1 : 0;
        break;
      case kFirstWeak:
      case kLastWeak:
        EXPECT_EQ(scan.return_index[i], 1) << "point " << i;
        ++pairs;
        strongest_agree += scan.return_index[i] == 1 ? 1 : 0;
        break;
      default:
        ADD_FAILURE() << "unexpected nebula return type " << int{ref.return_type};
    }
  }
  EXPECT_EQ(checked[0] + checked[1] + checked[2], reference_.size());
  EXPECT_GT(checked[0], reference_.size() / 2);  // most points come from interpolated blocks
  EXPECT_EQ(pairs, 376U);                        // 188 firings with two distinct echoes
  EXPECT_EQ(strongest_agree, pairs);
}

TEST_F(NebulaReference, DualReturnBookkeeping) {
  const auto& c = decoder_->counters();
  EXPECT_EQ(c.packets, 603U);
  EXPECT_EQ(c.lidar_packets, 603U);
  EXPECT_EQ(c.decode_errors, 0U);
  EXPECT_EQ(c.sequence_gaps, 0U);
  EXPECT_EQ(c.scans, 5U);
  EXPECT_EQ(decoder_->velodyne_counters().factory_byte_mismatches, 0U);  // 0x22 = VLP-16
  // Each firing is reported twice; the odd block repeats single echoes, which are dropped.
  const auto& v = decoder_->velodyne_counters();
  EXPECT_GT(v.duplicate_returns, 0U);
  std::size_t points = 0;
  for (const auto& scan : decoded_.scans) points += scan.size();
  EXPECT_EQ(points + v.zero_ranges + v.duplicate_returns + v.out_of_range, 603U * 384U);
  // Dual-return block pairs share their firing times: going from the even block's second
  // firing sequence to the odd block's first steps back by less than two sequences, never more.
  for (const auto& scan : decoded_.scans) {
    for (std::size_t i = 1; i < scan.size(); ++i) {
      ASSERT_GT(scan.t_offset_ns[i], scan.t_offset_ns[i - 1] - 2 * 55'296);
    }
    EXPECT_LT(scan.t_offset_ns.back(), 101'000'000);  // 600 rpm: one turn is 0.1 s
  }
}

}  // namespace
}  // namespace livod::drivers::velodyne

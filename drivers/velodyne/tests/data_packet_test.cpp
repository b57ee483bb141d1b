// Data packet decoding on synthetic packets with known contents: laser numbering per model,
// distance units, geometry with every correction, azimuth interpolation, dual returns.

#include "drivers/velodyne/data_packet.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <cmath>
#include <numbers>
#include <vector>

namespace livod::drivers::velodyne {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

class PacketBuilder {
 public:
  PacketBuilder() : bytes_(1206, std::byte{0}) {
    for (int b = 0; b < 12; ++b) block(b, 0xEEFF, 0);
  }
  PacketBuilder& block(int b, std::uint16_t flag, std::uint16_t azimuth) {
    put16(static_cast<std::size_t>(b) * 100, flag);
    put16(static_cast<std::size_t>(b) * 100 + 2, azimuth);
    return *this;
  }
  PacketBuilder& ret(int b, int channel, std::uint16_t raw, std::uint8_t intensity) {
    const std::size_t at =
        static_cast<std::size_t>(b) * 100 + 4 + static_cast<std::size_t>(channel) * 3;
    put16(at, raw);
    bytes_[at + 2] = std::byte{intensity};
    return *this;
  }
  PacketBuilder& tail(std::uint32_t toh_us, std::uint8_t mode, std::uint8_t factory) {
    for (int i = 0; i < 4; ++i)
      bytes_[1200 + static_cast<std::size_t>(i)] = static_cast<std::byte>(toh_us >> (8 * i));
    bytes_[1204] = std::byte{mode};
    bytes_[1205] = std::byte{factory};
    return *this;
  }
  [[nodiscard]] const std::vector<std::byte>& bytes() const { return bytes_; }

 private:
  void put16(std::size_t at, std::uint16_t v) {
    bytes_[at] = static_cast<std::byte>(v & 0xFF);
    bytes_[at + 1] = static_cast<std::byte>(v >> 8);
  }
  std::vector<std::byte> bytes_;
};

// The ROS velodyne model in Velodyne's own frame (x right, y forward), then livod's axes.
Eigen::Vector3d reference_point(double d, const LaserCorrection& l, double azimuth_deg) {
  const double a = azimuth_deg * kDeg - l.rot_correction_rad;
  const double w = l.vert_correction_rad;
  const double xy = d * std::cos(w) - l.vert_offset_m * std::sin(w);
  const double x_v = xy * std::sin(a) - l.horiz_offset_m * std::cos(a);
  const double y_v = xy * std::cos(a) + l.horiz_offset_m * std::sin(a);
  const double z = d * std::sin(w) + l.vert_offset_m * std::cos(w);
  return {y_v, -x_v, z};
}

std::vector<DecodedReturn> run(const DataPacketDecoder& decoder, const PacketBuilder& packet,
                               DataPacketResult& result) {
  std::vector<DecodedReturn> out(DataPacketDecoder::kMaxReturns);
  result = decoder.decode(packet.bytes(), 0.0, out);
  out.resize(result.count);
  return out;
}

TEST(DataPacket, GeometryAppliesEveryCorrection) {
  Calibration c = default_calibration(Model::kVlp16);
  LaserCorrection& l = c.lasers[3];
  l.vert_correction_rad = 5.0 * kDeg;
  l.rot_correction_rad = 2.0 * kDeg;
  l.dist_correction_m = 0.1;
  l.vert_offset_m = 0.2;
  l.horiz_offset_m = 0.05;
  const DataPacketDecoder decoder(Model::kVlp16, c, {});
  PacketBuilder p;
  for (int b = 0; b < 12; ++b) p.block(b, 0xEEFF, static_cast<std::uint16_t>(9000 + 40 * b));
  p.ret(0, 3, 5000, 10).tail(1000, 0x37, 0x22);  // block 0, firing 0, laser 3: 10 m + 0.1
  DataPacketResult r;
  const auto out = run(decoder, p, r);
  ASSERT_EQ(r.status, DataDecodeStatus::kOk);
  ASSERT_EQ(out.size(), 1U);
  // Firing at 3 x 2.304 us; the packet turns 440 counts over 11 x 110.592 us.
  const double azimuth_deg = 90.0 + 4.40 * (3 * 2.304) / (11 * 110.592);
  const Eigen::Vector3d expected = reference_point(10.1, l, azimuth_deg);
  EXPECT_NEAR(out[0].x, expected.x(), 2e-6);
  EXPECT_NEAR(out[0].y, expected.y(), 2e-6);
  EXPECT_NEAR(out[0].z, expected.z(), 2e-6);
  EXPECT_NEAR(out[0].distance_m, 10.1, 1e-6);
  EXPECT_NEAR(out[0].azimuth_rad, azimuth_deg * kDeg - 2.0 * kDeg, 1e-7);
  EXPECT_EQ(out[0].t_offset_ns, 3 * 2'304);
  EXPECT_EQ(out[0].laser, 3);
  EXPECT_EQ(out[0].ring, 9);  // 5 degrees: above the 8 negative beams and the 1 degree beam
  // Azimuth 90 degrees points right: y negative in livod's frame.
  EXPECT_LT(out[0].y, -9.0);
}

TEST(DataPacket, Vls128BanksAndFourMillimetreUnits) {
  const Calibration c = default_calibration(Model::kVls128);
  const DataPacketDecoder decoder(Model::kVls128, c, {});
  PacketBuilder p;
  const std::uint16_t flags[4] = {0xEEFF, 0xDDFF, 0xCCFF, 0xBBFF};
  for (int b = 0; b < 12; ++b) {
    p.block(b, flags[b % 4], static_cast<std::uint16_t>(1000 + 20 * (b / 4)));
    p.ret(b, 5, 2500, static_cast<std::uint8_t>(b));
  }
  p.tail(5000, 0x37, 0xA1);
  DataPacketResult r;
  const auto out = run(decoder, p, r);
  ASSERT_EQ(r.status, DataDecodeStatus::kOk);
  ASSERT_EQ(out.size(), 12U);
  const FiringTiming timing(Model::kVls128);
  const double rate_deg_per_ns = 0.40 / (2.0 * 20 * 2'665);  // 40 counts over two sequences
  for (int b = 0; b < 12; ++b) {
    const DecodedReturn& q = out[static_cast<std::size_t>(b)];
    const int laser = 32 * (b % 4) + 5;
    EXPECT_EQ(q.laser, laser);
    EXPECT_EQ(q.intensity, b);
    EXPECT_NEAR(q.distance_m, 10.0, 1e-6);  // 2500 x 4 mm
    EXPECT_EQ(q.t_offset_ns, timing.offset_ns(false, b, 5));
    const double azimuth_deg =
        10.0 + 0.2 * (b / 4) +
        rate_deg_per_ns * (timing.offset_ns(false, b, 5) - timing.block_reference_ns(false, b));
    const Eigen::Vector3d expected =
        reference_point(10.0, c.lasers[static_cast<std::size_t>(laser)], azimuth_deg);
    EXPECT_NEAR(q.x, expected.x(), 2e-6) << b;
    EXPECT_NEAR(q.y, expected.y(), 2e-6) << b;
    EXPECT_NEAR(q.z, expected.z(), 2e-6) << b;
  }
  // A VLP-16 flag in a VLS-128 packet is malformed.
  p.block(7, 0xAAFF, 1020);
  EXPECT_EQ(run(decoder, p, r).size(), 0U);
  EXPECT_EQ(r.status, DataDecodeStatus::kBadBlockFlag);
}

TEST(DataPacket, Vlp32cUsesRotationalCorrectionsAndLaserPairs) {
  const Calibration c = default_calibration(Model::kVlp32c);
  const DataPacketDecoder decoder(Model::kVlp32c, c, {});
  PacketBuilder p;
  for (int b = 0; b < 12; ++b) p.block(b, 0xEEFF, static_cast<std::uint16_t>(100 * b));
  p.ret(2, 0, 1000, 1).ret(2, 1, 1000, 2).tail(0, 0x37, 0x28);
  DataPacketResult r;
  const auto out = run(decoder, p, r);
  ASSERT_EQ(out.size(), 2U);
  EXPECT_EQ(out[0].t_offset_ns, out[1].t_offset_ns);  // lasers 0 and 1 fire together
  EXPECT_EQ(out[0].t_offset_ns, 2 * 55'296);
  for (int i = 0; i < 2; ++i) {
    const Eigen::Vector3d expected =
        reference_point(4.0, c.lasers[static_cast<std::size_t>(i)], 2.0);
    EXPECT_NEAR(out[static_cast<std::size_t>(i)].x, expected.x(), 2e-6);
    EXPECT_NEAR(out[static_cast<std::size_t>(i)].y, expected.y(), 2e-6);
  }
  // Laser 0 is rotated by -1.4 degrees, laser 1 by +4.2 degrees: they point 5.6 degrees apart.
  const double a0 = std::atan2(-out[0].y, out[0].x) / kDeg;
  const double a1 = std::atan2(-out[1].y, out[1].x) / kDeg;
  EXPECT_NEAR(a0 - a1, 5.6, 1e-4);
}

TEST(DataPacket, DualReturnPairsAreClassifiedAndDeduplicated) {
  const DataPacketDecoder decoder(Model::kVlp16, default_calibration(Model::kVlp16), {});
  PacketBuilder p;
  for (int b = 0; b < 12; ++b) p.block(b, 0xEEFF, static_cast<std::uint16_t>(200 * (b / 2)));
  p.ret(0, 0, 1000, 50).ret(1, 0, 1000, 50);  // one echo reported twice
  p.ret(0, 1, 2000, 10).ret(1, 1, 1500, 90);  // last (far, weak) and strongest (near)
  p.ret(0, 2, 3000, 40).ret(1, 2, 2500, 40);  // equal intensity: the nearer is primary
  p.ret(0, 3, 0, 0).ret(1, 3, 700, 5);        // only the odd block has an echo
  p.ret(2, 17, 900, 9);                       // second pair, firing 1
  p.tail(0, 0x39, 0x22);
  DataPacketResult r;
  const auto out = run(decoder, p, r);
  ASSERT_EQ(r.status, DataDecodeStatus::kOk);
  EXPECT_TRUE(r.dual);
  EXPECT_EQ(r.duplicates, 1);
  ASSERT_EQ(out.size(), 7U);
  // Block 0: channels 0, 1, 2; block 1: channels 1, 2, 3; block 2: channel 17.
  EXPECT_EQ(out[0].return_index, 0);                  // the single echo
  EXPECT_EQ(out[1].return_index, 1);                  // block 0 ch 1: weaker
  EXPECT_EQ(out[2].return_index, 1);                  // block 0 ch 2: farther, same intensity
  EXPECT_EQ(out[3].return_index, 0);                  // block 1 ch 1: stronger
  EXPECT_EQ(out[4].return_index, 0);                  // block 1 ch 2: nearer
  EXPECT_EQ(out[5].return_index, 0);                  // block 1 ch 3: alone
  EXPECT_EQ(out[3].t_offset_ns, out[1].t_offset_ns);  // the pair shares its firing time
  EXPECT_EQ(out[6].t_offset_ns, (2 + 1) * 55'296 + 1 * 2'304);
  // Both returns of a pair point the same way.
  EXPECT_NEAR(std::atan2(out[1].y, out[1].x), std::atan2(out[3].y, out[3].x), 1e-6);
}

TEST(DataPacket, RangeLimitsAndZeroRangesAreCounted) {
  DecodeSettings settings;
  settings.min_range_m = 1.0;
  settings.max_range_m = 50.0;
  const DataPacketDecoder decoder(Model::kHdl32e, default_calibration(Model::kHdl32e), settings);
  PacketBuilder p;
  for (int b = 0; b < 12; ++b) p.block(b, 0xEEFF, static_cast<std::uint16_t>(50 * b));
  p.ret(0, 0, 400, 1).ret(0, 1, 600, 1).ret(0, 2, 30000, 1).ret(0, 3, 20000, 1);
  p.tail(0, 0x37, 0x21);
  DataPacketResult r;
  const auto out = run(decoder, p, r);
  ASSERT_EQ(out.size(), 2U);     // 1.2 m and 40 m
  EXPECT_EQ(r.out_of_range, 2);  // 0.8 m and 60 m
  EXPECT_EQ(r.zero_ranges, 12 * 32 - 4);
}

TEST(DataPacket, VeloViewModeIsRestrictedToTheModelsVeloViewDefined) {
  DecodeSettings settings;
  settings.azimuth = AzimuthInterpolation::kVeloView;
  EXPECT_THROW(DataPacketDecoder(Model::kVls128, default_calibration(Model::kVls128), settings),
               std::exception);
  EXPECT_THROW(DataPacketDecoder(Model::kVlp16, default_calibration(Model::kHdl32e), {}),
               std::exception);
}

}  // namespace
}  // namespace livod::drivers::velodyne

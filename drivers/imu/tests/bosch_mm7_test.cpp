#include "drivers/imu/bosch_mm7.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <vector>

namespace livod::imu {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

std::vector<ImuSample> feed(CanImuDecoder& dec, const std::vector<CanRecord>& frames) {
  std::vector<ImuSample> out;
  for (const auto& f : frames) dec.on_frame(f, [&](const ImuSample& s) { out.push_back(s); });
  return out;
}

CanRecord frame(std::uint32_t id, std::array<std::uint8_t, 8> bytes, std::int64_t rx = 0) {
  CanRecord r;
  r.id = id;
  r.len = 8;
  r.rx_time_ns = rx;
  std::copy(bytes.begin(), bytes.end(), r.data.begin());
  return r;
}

TEST(BoschMm7, HandBuiltFramesDecodeWithThePublishedScales) {
  // Rates: raw 0x8000 + 200 = 1.0 deg/s; accelerations raw 0x8000 + 7845 counts:
  // 40613 * 0.000127465 - 4.1768 g. Counter 5 in bits 48-51, status 0.
  const std::uint16_t rate_raw = 0x8000 + 200;
  const std::uint16_t accel_raw = 0x8000 + 7845;
  auto bytes = [&](std::uint8_t temp) {
    return std::array<std::uint8_t, 8>{static_cast<std::uint8_t>(rate_raw & 0xFF),
                                       static_cast<std::uint8_t>(rate_raw >> 8),
                                       0,
                                       temp,
                                       static_cast<std::uint8_t>(accel_raw & 0xFF),
                                       static_cast<std::uint8_t>(accel_raw >> 8),
                                       0x05,
                                       0};
  };
  BoschMm7Decoder dec;
  const auto samples = feed(dec, {frame(0x174, bytes(75), 1000), frame(0x178, bytes(0), 1300),
                                  frame(0x17C, bytes(0), 1600)});
  ASSERT_EQ(samples.size(), 1u);
  const ImuSample& s = samples[0];
  const double rate = (rate_raw * 0.005 - 163.84) * kDeg;
  const double accel = (accel_raw * 0.000127465 - 4.1768) * 9.80665;
  EXPECT_NEAR(rate, 1.0 * kDeg, 1e-12);
  EXPECT_DOUBLE_EQ(s.gyro_rad_s.z(), rate);   // TX1: yaw
  EXPECT_DOUBLE_EQ(s.gyro_rad_s.x(), -rate);  // TX2: roll, reported left-handed, negated
  EXPECT_DOUBLE_EQ(s.gyro_rad_s.y(), rate);   // TX3: pitch
  EXPECT_DOUBLE_EQ(s.accel_m_s2.y(), accel);  // TX1: AY
  EXPECT_DOUBLE_EQ(s.accel_m_s2.x(), accel);  // TX2: AX
  EXPECT_DOUBLE_EQ(s.accel_m_s2.z(), accel);  // TX3: AZ
  EXPECT_NEAR(s.accel_m_s2.x(), 1.0 * 9.80665, 0.002);
  // No sensor clock: both stamps are TX1's receive time.
  EXPECT_EQ(s.stamp.host.ns, 1000);
  EXPECT_EQ(s.stamp.sensor.ns, 1000);
  EXPECT_FALSE(dec.has_sensor_clock());
  EXPECT_DOUBLE_EQ(dec.last_temperature_c(), 25.0);
  // Raw 0x8000 is zero rate.
  BoschMm7Decoder zero;
  auto z = bytes(0);
  z[0] = 0x00;
  z[1] = 0x80;
  const auto zs = feed(zero, {frame(0x174, z), frame(0x178, z), frame(0x17C, z)});
  ASSERT_EQ(zs.size(), 1u);
  EXPECT_DOUBLE_EQ(zs[0].gyro_rad_s.norm(), 0.0);
  // Temperature 0xFF flags CRC error / out of range.
  feed(zero, {frame(0x174, bytes(0xFF))});
  EXPECT_TRUE(std::isnan(zero.last_temperature_c()));
}

TEST(BoschMm7, EncodeDecodeRoundTripsWithinTheWireResolution) {
  BoschMm7Decoder dec;
  const Eigen::Vector3d accel(0.31, -2.5, 9.79);
  const Eigen::Vector3d gyro(0.2, -0.7, 1.1);
  std::vector<CanRecord> frames;
  for (std::uint8_t k = 0; k < 40; ++k) {
    const auto f = encode_bosch_mm7_sample(k, accel * (1.0 + 0.01 * k), gyro, 30.0);
    frames.insert(frames.end(), f.begin(), f.end());
  }
  const auto samples = feed(dec, frames);
  ASSERT_EQ(samples.size(), 40u);
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const Eigen::Vector3d a = accel * (1.0 + 0.01 * static_cast<double>(k));
    EXPECT_LE((samples[k].accel_m_s2 - a).cwiseAbs().maxCoeff(),
              0.5 * 0.000127465 * 9.80665 + 1e-9);
    EXPECT_LE((samples[k].gyro_rad_s - gyro).cwiseAbs().maxCoeff(), 0.5 * 0.005 * kDeg + 1e-12);
  }
  EXPECT_EQ(dec.counters().sequence_gaps, 0u);  // the 4-bit counter wrapped twice without gaps
  EXPECT_EQ(dec.counters().samples, 40u);
  EXPECT_EQ(dec.counters().frames, 120u);
}

TEST(BoschMm7, BrokenSamplesGapsAndStatusAreCounted) {
  const Eigen::Vector3d a(0, 0, 9.8);
  const Eigen::Vector3d g(0, 0, 0);
  BoschMm7Decoder dec;
  auto s0 = encode_bosch_mm7_sample(0, a, g, 20.0);
  auto s1 = encode_bosch_mm7_sample(1, a, g, 20.0);
  auto s4 = encode_bosch_mm7_sample(4, a, g, 20.0);  // samples 2 and 3 lost
  BoschMm7Status failing;
  failing.stat[3] = 0x02;  // AX signal failure
  auto s5 = encode_bosch_mm7_sample(5, a, g, 20.0, failing);
  auto s6 = encode_bosch_mm7_sample(6, a, g, 20.0);
  CanRecord short_frame = s6[1];
  short_frame.len = 6;
  std::vector<CanRecord> frames{s0[0], s0[1],       s0[2],
                                s1[0], s0[1],                // TX2 of another sample: broken
                                s4[0], s4[1],       s4[2],   // after 0: 1 broke, 2 and 3 lost
                                s5[0], s5[1],       s5[2],   // flagged invalid
                                s6[0], short_frame, s6[2]};  // malformed TX2, then TX3 alone
  const auto samples = feed(dec, frames);
  EXPECT_EQ(samples.size(), 2u);             // s0 and s4
  EXPECT_EQ(dec.counters().incomplete, 2u);  // s1 and s6
  EXPECT_EQ(dec.counters().invalid, 1u);
  EXPECT_EQ(dec.counters().malformed, 1u);
  // Completed samples carried counters 0, 4, 5: three missing (1 broke, 2 and 3 lost).
  EXPECT_EQ(dec.counters().sequence_gaps, 3u);
}

}  // namespace
}  // namespace livod::imu

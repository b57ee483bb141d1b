#include "drivers/imu/sbg_can.hpp"

#include <gtest/gtest.h>

#include <optional>

namespace livod::imu {
namespace {

// Feeds frames and returns the last sample emitted, if any.
std::optional<ImuSample> feed(CanImuDecoder& dec, std::initializer_list<CanRecord> frames) {
  std::optional<ImuSample> out;
  for (const auto& f : frames) dec.on_frame(f, [&](const ImuSample& s) { out = s; });
  return out;
}

CanRecord frame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) {
  CanRecord r;
  r.id = id;
  r.len = static_cast<std::uint8_t>(bytes.size());
  std::copy(bytes.begin(), bytes.end(), r.data.begin());
  return r;
}

TEST(SbgCan, EncodeDecodeRoundTripWithinOneLsb) {
  SbgCanDecoder dec;
  const Eigen::Vector3d acc(0.123, -9.806, 3.3);
  const Eigen::Vector3d gyr(0.0123, -1.5, 0.7777);
  auto frames = encode_sbg_sample(1'234'567, acc, gyr, 31.25);
  frames[0].rx_time_ns = 42;
  EXPECT_FALSE(feed(dec, {frames[0], frames[1]}));
  const auto s = feed(dec, {frames[2]});
  ASSERT_TRUE(s);
  EXPECT_EQ(s->stamp.sensor.ns, 1'234'567'000);
  EXPECT_EQ(s->stamp.host.ns, 42);
  EXPECT_LE((s->accel_m_s2 - acc).cwiseAbs().maxCoeff(), 0.005 + 1e-12);
  EXPECT_LE((s->gyro_rad_s - gyr).cwiseAbs().maxCoeff(), 0.0005 + 1e-12);
  EXPECT_NEAR(dec.last_temperature_c(), 31.25, 0.005);
  EXPECT_EQ(dec.counters().samples, 1u);
  EXPECT_TRUE(dec.has_sensor_clock());
  EXPECT_EQ(dec.frame_ids(), (std::vector<std::uint32_t>{0x120, 0x121, 0x122}));
}

TEST(SbgCan, KnownBytesDecodeToDocumentedScales) {
  // accel x = 0x03D4 = 980 counts = 9.80 m/s^2; gyro z = 0xFC18 = -1000 counts = -1.0 rad/s.
  SbgCanDecoder dec;
  const auto s =
      feed(dec, {frame(0x120, {0x10, 0x27, 0, 0, 0, 0, 0xC4, 0x09}),  // 10000 us, 25 C
                 frame(0x121, {0xD4, 0x03, 0, 0, 0, 0}), frame(0x122, {0, 0, 0, 0, 0x18, 0xFC})});
  ASSERT_TRUE(s);
  EXPECT_DOUBLE_EQ(s->accel_m_s2.x(), 9.80);
  EXPECT_DOUBLE_EQ(s->gyro_rad_s.z(), -1.0);
  EXPECT_NEAR(dec.last_temperature_c(), 25.0, 1e-12);
  EXPECT_EQ(s->stamp.sensor.ns, 10'000'000);
}

TEST(SbgCan, UnwrapsTheMicrosecondCounterAndCountsBrokenSamples) {
  SbgCanDecoder dec;
  const Eigen::Vector3d z = Eigen::Vector3d::Zero();
  auto a = encode_sbg_sample(0xFFFFFF00U, z, z, 0.0);
  feed(dec, {a[0], a[1], a[2]});
  auto b = encode_sbg_sample(0x00000100U, z, z, 0.0);  // 512 us later, across the wrap
  const auto s = feed(dec, {b[0], b[1], b[2]});
  ASSERT_TRUE(s);
  EXPECT_EQ(s->stamp.sensor.ns, ((std::int64_t{1} << 32) + 0x100) * 1000);
  EXPECT_EQ(dec.counters().counter_wraps, 1u);

  // INFO, then INFO again (ACCEL/GYRO lost): one incomplete sample; a short frame is malformed.
  auto c = encode_sbg_sample(1000, z, z, 0.0);
  CanRecord short_gyro = c[2];
  short_gyro.len = 2;
  feed(dec, {c[0], c[0], short_gyro});
  EXPECT_EQ(dec.counters().incomplete, 1u);
  EXPECT_EQ(dec.counters().malformed, 1u);
  // Frames of other devices on the bus, error and remote frames, and a 29-bit frame whose id
  // happens to equal INFO's are ignored.
  CanRecord other = frame(0x7FF, {0, 0, 0, 0, 0, 0, 0, 0});
  CanRecord extended_info = c[0];
  extended_info.extended = true;
  CanRecord error = c[0];
  error.error = true;
  EXPECT_FALSE(feed(dec, {other, extended_info, error}));
  EXPECT_EQ(dec.counters().malformed, 1u);
  EXPECT_EQ(dec.counters().frames, 9u);
}

}  // namespace
}  // namespace livod::imu

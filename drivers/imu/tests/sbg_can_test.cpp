#include "drivers/imu/sbg_can.hpp"

#include <gtest/gtest.h>

namespace livod::imu {
namespace {

TEST(SbgCan, EncodeDecodeRoundTripWithinOneLsb) {
  SbgCanDecoder dec;
  const Eigen::Vector3d acc(0.123, -9.806, 3.3);
  const Eigen::Vector3d gyr(0.0123, -1.5, 0.7777);
  auto frames = encode_sbg_sample(1'234'567, acc, gyr, 31.25);
  frames[0].rx_time_ns = 42;
  EXPECT_FALSE(dec.on_frame(frames[0]));
  EXPECT_FALSE(dec.on_frame(frames[1]));
  const auto s = dec.on_frame(frames[2]);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->imu.stamp.sensor.ns, 1'234'567'000);
  EXPECT_EQ(s->imu.stamp.host.ns, 42);
  EXPECT_LE((s->imu.accel_m_s2 - acc).cwiseAbs().maxCoeff(), 0.005 + 1e-12);
  EXPECT_LE((s->imu.gyro_rad_s - gyr).cwiseAbs().maxCoeff(), 0.0005 + 1e-12);
  EXPECT_NEAR(s->temperature_c, 31.25, 0.005);
  EXPECT_EQ(dec.counters().samples, 1u);
}

TEST(SbgCan, KnownBytesDecodeToDocumentedScales) {
  // accel x = 0x03D4 = 980 counts = 9.80 m/s^2; gyro z = 0xFC18 = -1000 counts = -1.0 rad/s.
  SbgCanDecoder dec;
  CanPayload info{0x120, 8, {0x10, 0x27, 0, 0, 0, 0, 0xC4, 0x09}, 0};  // t = 10000 us, 25.00 C
  CanPayload accel{0x121, 6, {0xD4, 0x03, 0, 0, 0, 0}, 0};
  CanPayload gyro{0x122, 6, {0, 0, 0, 0, 0x18, 0xFC}, 0};
  dec.on_frame(info);
  dec.on_frame(accel);
  const auto s = dec.on_frame(gyro);
  ASSERT_TRUE(s);
  EXPECT_DOUBLE_EQ(s->imu.accel_m_s2.x(), 9.80);
  EXPECT_DOUBLE_EQ(s->imu.gyro_rad_s.z(), -1.0);
  EXPECT_NEAR(s->temperature_c, 25.0, 1e-12);
  EXPECT_EQ(s->imu.stamp.sensor.ns, 10'000'000);
}

TEST(SbgCan, UnwrapsTheMicrosecondCounterAndCountsBrokenSamples) {
  SbgCanDecoder dec;
  const Eigen::Vector3d z = Eigen::Vector3d::Zero();
  auto a = encode_sbg_sample(0xFFFFFF00U, z, z, 0.0);
  for (auto& f : a) dec.on_frame(f);
  auto b = encode_sbg_sample(0x00000100U, z, z, 0.0);  // 512 us later, across the wrap
  dec.on_frame(b[0]);
  dec.on_frame(b[1]);
  const auto s = dec.on_frame(b[2]);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->imu.stamp.sensor.ns, ((std::int64_t{1} << 32) + 0x100) * 1000);
  EXPECT_EQ(dec.counters().counter_wraps, 1u);

  // INFO, then INFO again (ACCEL/GYRO lost): one incomplete sample; a short frame is malformed.
  auto c = encode_sbg_sample(1000, z, z, 0.0);
  dec.on_frame(c[0]);
  dec.on_frame(c[0]);
  CanPayload short_gyro = c[2];
  short_gyro.len = 2;
  dec.on_frame(short_gyro);
  EXPECT_EQ(dec.counters().incomplete, 1u);
  EXPECT_EQ(dec.counters().malformed, 1u);
  // Frames of other devices on the bus are ignored.
  EXPECT_FALSE(dec.on_frame(CanPayload{0x7FF, 8, {}, 0}));
  EXPECT_EQ(dec.counters().malformed, 1u);
}

}  // namespace
}  // namespace livod::imu

// The simulator's position packet encoder is the inverse of livod's decoder: the fields decode
// back, and HDL-32E motion words decode to the encoded rates and specific forces within half an
// LSB per axis, with the real sensor's word tags and saturation.

#include "tools/sim/velodyne_position_encoder.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "core/units.hpp"
#include "drivers/velodyne/position_packet.hpp"
#include "drivers/velodyne/wire.hpp"

namespace livod::sim {
namespace {

namespace vel = drivers::velodyne;

constexpr double kGyroLsbRadS = vel::kHdlGyroDegPerSecPerLsb * kDegToRad;
constexpr double kAccelLsbMS2 = vel::kHdlAccelGPerLsb * kStandardGravity;

vel::PositionPacket decode(const std::vector<std::byte>& payload) {
  const auto r = vel::decode_position_packet(payload);
  EXPECT_EQ(r.status, vel::PositionDecodeStatus::kOk);
  return r.packet;
}

TEST(VelodynePositionEncoder, FieldsDecodeBack) {
  const std::uint32_t toh = 2'345'678'901;  // 39 min 5.678901 s past the hour
  const auto payload = encode_position_packet(toh, nullptr);
  ASSERT_EQ(payload.size(), vel::wire::kPositionPacketSize);
  const vel::PositionPacket p = decode(payload);
  EXPECT_EQ(p.toh_us, toh);
  ASSERT_TRUE(p.pps.has_value());
  EXPECT_EQ(*p.pps, vel::PpsStatus::kAbsent);
  EXPECT_EQ(p.nmea, "$GPRMC,003905,V,,,,,,,,,,N*5C\r\n");
  // Without a fix the receiver has no date: the decoder takes no time anchor from it.
  EXPECT_FALSE(p.rmc.has_value());
  for (const auto& m : p.motion) {  // no motion sensors: all words zero
    EXPECT_EQ(m.gyro_deg_s, 0.0);
    EXPECT_EQ(m.accel_x_g, 0.0);
    EXPECT_EQ(m.accel_y_g, 0.0);
  }
}

TEST(VelodynePositionEncoder, MotionWordsDecodeWithinHalfAnLsb) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> gyro(-3.0, 3.0);     // rad/s, inside +-200 deg/s
  std::uniform_real_distribution<double> accel(-20.0, 20.0);  // m/s^2, inside +-2.5 g
  const std::array<double, 3> temperatures{35.1, 37.4, 41.1};
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d w(gyro(rng), gyro(rng), gyro(rng));
    const Eigen::Vector3d a(accel(rng), accel(rng), accel(rng));
    const auto words = encode_hdl32e_motion(w, a, temperatures);
    const auto payload = encode_position_packet(1000, &words);
    const vel::PositionPacket p = decode(payload);
    const vel::ImuVectors v = vel::hdl32e_imu_in_lidar_frame(p);
    ASSERT_LE((v.gyro_rad_s - w).cwiseAbs().maxCoeff(), 0.5 * kGyroLsbRadS * (1 + 1e-9)) << i;
    ASSERT_LE((v.accel_m_s2 - a).cwiseAbs().maxCoeff(), 0.5 * kAccelLsbMS2 * (1 + 1e-9)) << i;
    for (std::size_t s = 0; s < 3; ++s) {
      EXPECT_NEAR(p.motion[s].temperature_c, temperatures[s], 0.5 * vel::kHdlTemperatureCPerLsb);
    }
  }
}

// Each axis on its own goes where the decoder's mapping (docs/drivers/velodyne.md) says: the
// words of the two accelerometers that measure it, with the signs of the Velodyne frame.
TEST(VelodynePositionEncoder, AxesLandOnTheDocumentedWords) {
  const std::array<double, 3> t{25.0, 25.0, 25.0};
  const auto g = kStandardGravity;
  // +z (gravity on an upright sensor): accel x of sensors 1 and 2.
  auto w = encode_hdl32e_motion(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, g), t);
  EXPECT_EQ(w[2] & 0x0FFF, 819);
  EXPECT_EQ(w[6] & 0x0FFF, 819);
  EXPECT_EQ(w[3] & 0x0FFF, 0);
  EXPECT_EQ(w[10] & 0x0FFF, 0);
  // +x (forward = Velodyne +y): -accel y of sensors 2 and 3.
  w = encode_hdl32e_motion(Eigen::Vector3d::Zero(), Eigen::Vector3d(g, 0, 0), t);
  EXPECT_EQ(w[7] & 0x0FFF, 0x1000 - 819);
  EXPECT_EQ(w[11] & 0x0FFF, 0x1000 - 819);
  // +y (left = Velodyne -x): accel y of sensor 1, -accel x of sensor 3.
  w = encode_hdl32e_motion(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, g, 0), t);
  EXPECT_EQ(w[3] & 0x0FFF, 819);
  EXPECT_EQ(w[10] & 0x0FFF, 0x1000 - 819);
  // Rates: x = gyro 1, y = -gyro 2, z = -gyro 3 (100 LSB each).
  const double r = 100 * kGyroLsbRadS;
  w = encode_hdl32e_motion(Eigen::Vector3d(r, 2 * r, 3 * r), Eigen::Vector3d::Zero(), t);
  EXPECT_EQ(w[0] & 0x0FFF, 100);
  EXPECT_EQ(w[4] & 0x0FFF, 0x1000 - 200);
  EXPECT_EQ(w[8] & 0x0FFF, 0x1000 - 300);
  // The upper nibble tags each word with its place in the sensor's group, as the real sensor.
  for (std::size_t i = 0; i < w.size(); ++i) EXPECT_EQ(w[i] >> 12, i % 4) << i;
}

TEST(VelodynePositionEncoder, BeyondTheRangeTheWordsSaturate) {
  const std::array<double, 3> t{25.0, 25.0, 25.0};
  const auto words =
      encode_hdl32e_motion(Eigen::Vector3d(10.0, 0, 0), Eigen::Vector3d(0, 0, 40.0), t);
  const vel::PositionPacket p = decode(encode_position_packet(0, &words));
  EXPECT_NEAR(p.motion[0].gyro_deg_s, 2047 * vel::kHdlGyroDegPerSecPerLsb, 1e-9);
  EXPECT_NEAR(p.motion[0].accel_x_g, 2047 * vel::kHdlAccelGPerLsb, 1e-9);
}

}  // namespace
}  // namespace livod::sim

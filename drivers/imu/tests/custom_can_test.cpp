#include "drivers/imu/custom_can.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <vector>

#include "drivers/imu/bosch_mm7.hpp"
#include "drivers/imu/sbg_can.hpp"

namespace livod::imu {
namespace {

std::vector<ImuSample> feed(CanImuDecoder& dec, const std::vector<CanRecord>& frames) {
  std::vector<ImuSample> out;
  for (const auto& f : frames) dec.on_frame(f, [&](const ImuSample& s) { out.push_back(s); });
  return out;
}

// The SBG layout written as a custom spec: i16 Intel signals, 0.01 m/s^2 and 0.001 rad/s.
CustomCanSpec sbg_as_custom() {
  CustomCanSpec spec;
  for (int a = 0; a < 3; ++a) {
    spec.signals.push_back(
        {static_cast<ImuAxis>(a), 0x121, {16 * a, 16, false, true}, 0.01, 0.0, ImuUnit::m_s2});
    spec.signals.push_back({static_cast<ImuAxis>(3 + a),
                            0x122,
                            {16 * a, 16, false, true},
                            0.001,
                            0.0,
                            ImuUnit::rad_s});
  }
  spec.sample_id = 0x122;
  return spec;
}

TEST(CustomCan, AYamlDescribedSbgDecodesLikeTheSbgDecoder) {
  CustomCanDecoder custom(sbg_as_custom());
  SbgCanDecoder sbg;
  std::vector<CanRecord> frames;
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector3d a(0.01 * k, -9.81 + 0.02 * k, 0.5);
    const Eigen::Vector3d g(-0.003 * k, 0.1, 0.001 * k);
    auto f = encode_sbg_sample(static_cast<std::uint32_t>(5000 * k), a, g, 20.0);
    for (auto& r : f) r.rx_time_ns = 1'000'000 * k + static_cast<std::int64_t>(&r - f.data());
    frames.insert(frames.end(), f.begin(), f.end());
  }
  const auto a = feed(custom, frames);
  const auto b = feed(sbg, frames);
  ASSERT_EQ(a.size(), 50u);
  ASSERT_EQ(b.size(), 50u);
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].accel_m_s2, b[k].accel_m_s2);
    EXPECT_EQ(a[k].gyro_rad_s, b[k].gyro_rad_s);
    // The custom decoder has no clock: stamped with the first frame of the sample (ACCEL).
    EXPECT_EQ(a[k].stamp.host.ns, b[k].stamp.host.ns + 1);
    EXPECT_EQ(a[k].stamp.sensor.ns, a[k].stamp.host.ns);
  }
  EXPECT_EQ(custom.counters().frames, 100u);  // INFO frames are not the custom decoder's
  EXPECT_EQ(custom.frame_ids(), (std::vector<std::uint32_t>{0x121, 0x122}));
}

TEST(CustomCan, BoschLayoutInDegreesAndGWithMotorolaVariantsRoundTrips) {
  // The MM7 signals (unsigned, offset) as a custom spec: the same values except the roll sign.
  CustomCanSpec spec;
  const std::array<std::uint32_t, 3> ids{0x178, 0x17C, 0x174};  // x, y, z frames
  const std::array<std::uint32_t, 3> accel_ids{0x178, 0x174, 0x17C};
  for (int a = 0; a < 3; ++a) {
    spec.signals.push_back({static_cast<ImuAxis>(a),
                            accel_ids[static_cast<std::size_t>(a)],
                            {32, 16, false, false},
                            0.000127465,
                            -4.1768,
                            ImuUnit::g});
    spec.signals.push_back({static_cast<ImuAxis>(3 + a),
                            ids[static_cast<std::size_t>(a)],
                            {0, 16, false, false},
                            0.005,
                            -163.84,
                            ImuUnit::deg_s});
  }
  spec.sample_id = 0x17C;
  CustomCanDecoder custom(spec);
  BoschMm7Decoder bosch;
  const Eigen::Vector3d acc(1.0, -2.0, 9.7);
  const Eigen::Vector3d gyr(0.3, -0.2, 0.1);
  auto f = encode_bosch_mm7_sample(3, acc, gyr, 25.0);
  const auto a = feed(custom, {f.begin(), f.end()});
  const auto b = feed(bosch, {f.begin(), f.end()});
  ASSERT_EQ(a.size(), 1u);
  ASSERT_EQ(b.size(), 1u);
  EXPECT_NEAR((a[0].accel_m_s2 - b[0].accel_m_s2).norm(), 0.0, 1e-12);
  EXPECT_NEAR(a[0].gyro_rad_s.x(), -b[0].gyro_rad_s.x(), 1e-12);  // the raw (left-handed) roll
  EXPECT_NEAR(a[0].gyro_rad_s.y(), b[0].gyro_rad_s.y(), 1e-12);

  // Motorola, signed, 12-bit and 29-bit identifiers: encode -> decode within one LSB.
  CustomCanSpec m;
  for (int a2 = 0; a2 < 6; ++a2) {
    const bool accel = a2 < 3;
    m.signals.push_back({static_cast<ImuAxis>(a2),
                         accel ? 0x18FF0001u : 0x18FF0002u,
                         {7 + 16 * (a2 % 3), 12, true, true},
                         accel ? 0.01 : 0.002,
                         0.0,
                         accel ? ImuUnit::m_s2 : ImuUnit::rad_s});
  }
  m.sample_id = 0x18FF0002u;
  CustomCanDecoder motorola(m);
  const auto frames = encode_custom_sample(m, acc, gyr);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_TRUE(frames[0].extended);
  const auto s = feed(motorola, frames);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_LE((s[0].accel_m_s2 - acc).cwiseAbs().maxCoeff(), 0.005 + 1e-12);
  EXPECT_LE((s[0].gyro_rad_s - gyr).cwiseAbs().maxCoeff(), 0.001 + 1e-12);
}

TEST(CustomCan, IncompleteAndShortFramesAreCountedAndInvalidSpecsRejected) {
  CustomCanDecoder dec(sbg_as_custom());
  auto f = encode_sbg_sample(0, Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(0.1, 0.2, 0.3), 0.0);
  CanRecord short_gyro = f[2];
  short_gyro.len = 4;
  EXPECT_TRUE(feed(dec, {f[2]}).empty());  // GYRO without ACCEL: incomplete
  EXPECT_TRUE(feed(dec, {f[1], short_gyro}).empty());
  EXPECT_EQ(dec.counters().incomplete, 1u);
  EXPECT_EQ(dec.counters().malformed, 1u);
  EXPECT_EQ(feed(dec, {f[1], f[2]}).size(), 1u);  // ACCEL is still pending from before: fine

  CustomCanSpec bad = sbg_as_custom();
  bad.signals.pop_back();                       // no gyro_z
  bad.signals[0].bits = {60, 16, false, true};  // beyond 64 bits
  bad.signals[1].unit = ImuUnit::g;             // accel unit on a gyro axis
  bad.sample_id = 0x300;                        // carries no signal
  const auto problems = check_spec(bad);
  EXPECT_EQ(problems.size(), 4u);
  EXPECT_THROW(CustomCanDecoder{bad}, std::invalid_argument);
}

}  // namespace
}  // namespace livod::imu

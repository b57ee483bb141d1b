#include "estimator/imu/initializer.hpp"

#include <gtest/gtest.h>

#include <random>

namespace livod::estimator {
namespace {

ImuSample sample(std::int64_t t_ns, const Eigen::Vector3d& gyro, const Eigen::Vector3d& acc) {
  ImuSample s;
  s.stamp.mapped = MappedTime(t_ns);
  s.gyro_rad_s = gyro;
  s.accel_m_s2 = acc;
  return s;
}

TEST(ImuInitializer, StaticWindowGivesGravityAndGyroBias) {
  ImuParams params;
  ImuInitializer init(params);
  std::mt19937 rng(1);
  std::normal_distribution<double> n(0.0, 0.01);
  const Eigen::Vector3d bias(0.003, -0.002, 0.001);
  const Eigen::Vector3d up = Eigen::Vector3d(0.1, -0.2, 0.97).normalized();
  bool done = false;
  for (int i = 0; i < 30; ++i) {
    done = init.add(sample(i * 5'000'000, bias + Eigen::Vector3d(n(rng), n(rng), n(rng)) * 0.1,
                           up * 9.81 + Eigen::Vector3d(n(rng), n(rng), n(rng))));
  }
  ASSERT_TRUE(done) << init.status();
  const auto& b = *init.result();
  EXPECT_LT((b.x.bias_gyro - bias).norm(), 1e-3);
  EXPECT_LT((b.x.gravity_world + up * 9.81).norm(), 0.01);
  EXPECT_EQ(init.time().ns, 29 * 5'000'000);
  EXPECT_EQ(init.rejections(), 0);
}

TEST(ImuInitializer, RefusesWhileMovingAndSaysSo) {
  ImuParams params;
  ImuInitializer init(params);
  for (int i = 0; i < 200; ++i) {
    const double t = i * 0.005;
    init.add(sample(i * 5'000'000, Eigen::Vector3d(0.0, 0.0, 1.5 * std::sin(6.0 * t)),
                    Eigen::Vector3d(2.0 * std::sin(9.0 * t), 0.0, 9.81)));
  }
  EXPECT_FALSE(init.done());
  EXPECT_GT(init.rejections(), 0);
  EXPECT_NE(init.status().find("moving"), std::string::npos) << init.status();
  // Once the platform stops, initialisation completes.
  for (int i = 200; i < 260 && !init.done(); ++i) {
    init.add(sample(i * 5'000'000, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 0.0, 9.81)));
  }
  EXPECT_TRUE(init.done());
}

TEST(ImuInitializer, DetectsAccelerometerInG) {
  ImuInitializer init(ImuParams{});
  for (int i = 0; i < 40; ++i) {
    init.add(sample(i * 5'000'000, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 0.0, 1.0)));
  }
  EXPECT_FALSE(init.done());
  EXPECT_NE(init.status().find("g to m/s^2"), std::string::npos) << init.status();
}

TEST(ImuInitializer, GravityAlignPutsGravityOnMinusZ) {
  ImuParams params;
  params.gravity_align = true;
  params.init_time_s = 0.1;
  ImuInitializer init(params);
  const Eigen::Vector3d up = Eigen::Vector3d(0.3, 0.1, 0.9).normalized();
  for (int i = 0; i < 40 && !init.done(); ++i) {
    init.add(sample(i * 5'000'000, Eigen::Vector3d::Zero(), up * 9.8));
  }
  ASSERT_TRUE(init.done());
  const auto& x = init.result()->x;
  EXPECT_LT((x.gravity_world - Eigen::Vector3d(0, 0, -9.81)).norm(), 1e-12);
  // The measured specific force, rotated into the world, points straight up.
  EXPECT_LT((x.R_world_imu * up - Eigen::Vector3d::UnitZ()).norm(), 1e-9);
}

}  // namespace
}  // namespace livod::estimator

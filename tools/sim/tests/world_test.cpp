#include "tools/sim/world.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace livod::sim {
namespace {

TEST(World, RayHitsTheNearestFaceOfABoxWithTheRightNormal) {
  World w;
  w.add_box({5.0, 0.0, 0.0}, {1.0, 2.0, 3.0}, 0.0, Surface{});
  w.build();
  Hit hit;
  ASSERT_TRUE(w.intersect({0, 0, 0}, {1, 0, 0}, 0.0, 100.0, hit));
  EXPECT_NEAR(hit.range, 4.0, 1e-12);
  EXPECT_NEAR(hit.normal.x(), -1.0, 1e-12);
  EXPECT_FALSE(w.intersect({0, 0, 0}, {-1, 0, 0}, 0.0, 100.0, hit));
  EXPECT_FALSE(w.intersect({0, 0, 0}, {1, 0, 0}, 0.0, 3.9, hit));  // beyond max range
}

TEST(World, RotatedBoxCylinderAndSphereAgreeWithClosedForms) {
  World w;
  w.add_box({0.0, 10.0, 0.0}, {1.0, 1.0, 1.0}, M_PI / 4, Surface{});
  w.add_cylinder({-10.0, 0.0, -5.0}, 0.5, 10.0, Surface{});
  w.add_sphere({0.0, 0.0, 20.0}, 2.0, Surface{});
  w.build();
  Hit hit;
  ASSERT_TRUE(w.intersect({0, 0, 0}, {0, 1, 0}, 0.0, 100.0, hit));
  EXPECT_NEAR(hit.range, 10.0 - std::sqrt(2.0), 1e-12);  // a corner of the 45 deg box
  ASSERT_TRUE(w.intersect({0, 0, 0}, {-1, 0, 0}, 0.0, 100.0, hit));
  EXPECT_NEAR(hit.range, 9.5, 1e-12);
  EXPECT_NEAR(hit.normal.x(), 1.0, 1e-12);
  ASSERT_TRUE(w.intersect({0, 0, 0}, {0, 0, 1}, 0.0, 100.0, hit));
  EXPECT_NEAR(hit.range, 18.0, 1e-12);
  EXPECT_NEAR(hit.normal.z(), -1.0, 1e-12);
}

TEST(World, BvhGivesTheSameAnswerAsBruteForce) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-30.0, 30.0);
  std::uniform_real_distribution<double> size(0.2, 3.0);
  World bvh;
  std::vector<World> singles(200);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d c(pos(rng), pos(rng), pos(rng) * 0.2);
    const Eigen::Vector3d h(size(rng), size(rng), size(rng));
    const double yaw = pos(rng);
    bvh.add_box(c, h, yaw, Surface{});
    singles[i].add_box(c, h, yaw, Surface{});
    singles[i].build();
  }
  bvh.build();
  std::normal_distribution<double> n(0.0, 1.0);
  for (int r = 0; r < 2000; ++r) {
    const Eigen::Vector3d dir = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    Hit a;
    const bool hit_bvh = bvh.intersect({0, 0, 0}, dir, 0.0, 200.0, a);
    double best = 1e300;
    for (const auto& s : singles) {
      Hit b;
      if (s.intersect({0, 0, 0}, dir, 0.0, 200.0, b)) {
        best = std::min(best, b.range);
      }
    }
    ASSERT_EQ(hit_bvh, best < 1e300);
    if (hit_bvh) {
      EXPECT_NEAR(a.range, best, 1e-9);
    }
  }
}

TEST(World, AlbedoIsDeterministicBoundedAndTextured) {
  Surface s;
  s.texture_scale = 2.0F;
  double min = 1.0;
  double max = 0.0;
  double grad_sum = 0.0;
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector3d p(0.013 * i, 0.5, 1.0);
    const float a = World::albedo(s, p);
    EXPECT_EQ(a, World::albedo(s, p));
    min = std::min<double>(min, a);
    max = std::max<double>(max, a);
    grad_sum += std::abs(World::albedo(s, p + Eigen::Vector3d(0.01, 0, 0)) - a);
  }
  EXPECT_GE(min, 0.02);
  EXPECT_LE(max, 0.98);
  EXPECT_GT(max - min, 0.3);         // enough contrast
  EXPECT_GT(grad_sum / 1000, 1e-3);  // and gradient everywhere on average
}

}  // namespace
}  // namespace livod::sim

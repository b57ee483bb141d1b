// The LiDAR return model every simulated sensor uses (lidar_return.hpp): noise, signal-limited
// detection, noise growing with range and incidence, range walk, mixed pixels at depth edges,
// foliage and moving objects.

#include "tools/sim/lidar_return.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "tools/sim/scenario.hpp"

namespace livod::sim {
namespace {

Surface surface(float reflectivity) {
  Surface s;
  s.reflectivity = reflectivity;
  return s;
}

// A wall facing the origin at x = distance (normal -x), reflectivity rho.
World wall(double distance, float rho) {
  World w;
  w.add_box({distance + 0.5, 0.0, 0.0}, {0.5, 200.0, 200.0}, 0.0, surface(rho));
  w.build();
  return w;
}

struct Stats {
  double mean = 0.0;
  double std = 0.0;
  int valid = 0;
};

Stats fire(const World& world, const Eigen::Vector3d& dir, const RangeModel& model, int n,
           const MovingObjects* movers = nullptr, double time = 0.0, std::uint64_t seed = 1) {
  SceneContext scene;
  scene.world = &world;
  scene.movers = movers;
  std::mt19937_64 rng(seed);
  double sum = 0.0, sum2 = 0.0;
  Stats s;
  for (int i = 0; i < n; ++i) {
    const LidarReturn r = measure_return(scene, time, Eigen::Vector3d::Zero(), dir.normalized(),
                                         Eigen::Vector3d::UnitZ(), model, rng);
    if (!r.valid) continue;
    ++s.valid;
    sum += r.range_m;
    sum2 += r.range_m * r.range_m;
  }
  if (s.valid > 0) {
    s.mean = sum / s.valid;
    s.std = std::sqrt(std::max(0.0, sum2 / s.valid - s.mean * s.mean));
  }
  return s;
}

RangeModel plain(double sigma) {
  RangeModel m;
  m.sigma_m = sigma;
  m.dropout_probability = 0.0;
  return m;
}

TEST(LidarReturn, PlainModelIsGaussianAroundTheSurface) {
  const World w = wall(10.0, 0.5F);
  const Stats s = fire(w, Eigen::Vector3d::UnitX(), plain(0.02), 20000);
  EXPECT_EQ(s.valid, 20000);
  EXPECT_NEAR(s.mean, 10.0, 0.001);
  EXPECT_NEAR(s.std, 0.02, 0.001);
}

TEST(LidarReturn, DropoutsAndRangeLimits) {
  RangeModel m = plain(0.0);
  m.dropout_probability = 0.25;
  EXPECT_NEAR(fire(wall(10.0, 0.5F), Eigen::Vector3d::UnitX(), m, 8000).valid, 6000, 200);
  m.dropout_probability = 0.0;
  m.max_range_m = 9.0;
  EXPECT_EQ(fire(wall(10.0, 0.5F), Eigen::Vector3d::UnitX(), m, 100).valid, 0);
}

// An 80 % target head-on returns up to max_range_m, a 10 % one to max_range sqrt(0.1 / 0.8)
// (the OS1 datasheet's 120 m / 40 m pair), and a surface seen at incidence alpha as one of
// reflectivity rho cos(alpha).
TEST(LidarReturn, DetectionLimitFollowsReflectivityAndIncidence) {
  RangeModel m = plain(0.0);
  m.detection_limited = true;
  m.max_range_m = 120.0;
  const double limit10 = 120.0 * std::sqrt(0.1 / 0.8);  // 42.4 m
  EXPECT_EQ(fire(wall(limit10 - 1.0, 0.1F), Eigen::Vector3d::UnitX(), m, 10).valid, 10);
  EXPECT_EQ(fire(wall(limit10 + 1.0, 0.1F), Eigen::Vector3d::UnitX(), m, 10).valid, 0);
  // 60 deg off the wall's normal: cos = 0.5, a 40 % target acts as 20 %: limit 60 m along the
  // ray, i.e. the wall at 30 m.
  const Eigen::Vector3d slanted(std::cos(M_PI / 3), std::sin(M_PI / 3), 0.0);
  EXPECT_EQ(fire(wall(29.0, 0.4F), slanted, m, 10).valid, 10);
  EXPECT_EQ(fire(wall(31.0, 0.4F), slanted, m, 10).valid, 0);
}

// sigma = hypot(sigma_m, sigma_at_limit (r / r_limit)^1.2); weak echoes read long by up to
// intensity_bias_m (r / r_limit)^2.
TEST(LidarReturn, NoiseAndRangeWalkGrowTowardsTheDetectionLimit) {
  RangeModel m = plain(0.015);
  m.detection_limited = true;
  m.max_range_m = 120.0;
  m.sigma_at_limit_m = 0.10;
  m.intensity_bias_m = 0.03;
  for (const double d : {5.0, 40.0, 80.0}) {
    const double limit = 120.0 * std::sqrt(0.5 / 0.8);
    const double q = d / limit;
    const Stats s = fire(wall(d, 0.5F), Eigen::Vector3d::UnitX(), m, 20000);
    ASSERT_EQ(s.valid, 20000);
    EXPECT_NEAR(s.std, std::hypot(0.015, 0.10 * std::pow(q, 1.2)), 0.004) << d;
    EXPECT_NEAR(s.mean - d, 0.03 * q * q, 0.003) << d;
  }
}

// A footprint straddling a depth edge: echoes within a pulse length merge into a point between
// the surfaces (a mixed pixel); farther apart the stronger one is reported.
TEST(LidarReturn, MixedPixelsAtDepthEdges) {
  RangeModel m = plain(0.0);
  m.divergence_h_rad = 2e-3;  // 1 cm half width at 10 m
  m.pulse_length_m = 0.75;
  const auto scene_with = [](double behind) {
    World w;
    // A box whose front face at x = 9.5 ends at y = -0.005 (it fills y < -0.005), a wall behind.
    w.add_box({9.75, -5.005, 0.0}, {0.25, 5.0, 5.0}, 0.0, surface(0.5F));
    w.add_box({9.5 + behind + 0.5, 0.0, 0.0}, {0.5, 50.0, 50.0}, 0.0, surface(0.5F));
    w.build();
    return w;
  };
  // The central ray and one half-maximum ray see the wall 0.4 m behind, one sees the box.
  const Stats near = fire(scene_with(0.4), Eigen::Vector3d::UnitX(), m, 10);
  ASSERT_EQ(near.valid, 10);
  EXPECT_GT(near.mean, 9.55);
  EXPECT_LT(near.mean, 9.85);
  // 5.4 m behind: two echoes; the wall's (two rays of three) is the stronger. The off-axis ray
  // meets the wall 1 mrad off the normal, 14.9 / cos(1 mrad) = 14.9 + 7.5 um away: the merged
  // echo reads a few um long, nothing of the box's 9.5 m.
  const Stats far = fire(scene_with(5.4), Eigen::Vector3d::UnitX(), m, 10);
  ASSERT_EQ(far.valid, 10);
  EXPECT_NEAR(far.mean, 14.9, 1e-5);
  // Without divergence the ray sees exactly what is on its axis.
  EXPECT_NEAR(fire(scene_with(0.4), Eigen::Vector3d::UnitX(), plain(0.0), 1).mean, 9.9, 1e-9);
}

// A beam in a crown ends on a leaf somewhere inside it or passes through: ranges spread over the
// crown's depth, and some reach the wall behind.
TEST(LidarReturn, FoliageIsAVolume) {
  World w;
  Surface leaves = surface(0.35F);
  leaves.foliage_free_path_m = 1.0F;
  w.add_sphere({10.0, 0.0, 0.0}, 1.5, leaves);
  w.add_box({20.5, 0.0, 0.0}, {0.5, 50.0, 50.0}, 0.0, surface(0.5F));
  w.build();
  SceneContext scene;
  scene.world = &w;
  std::mt19937_64 rng(5);
  int in_crown = 0, behind = 0;
  double min_r = 1e9, max_r = 0.0;
  for (int i = 0; i < 4000; ++i) {
    const LidarReturn r =
        measure_return(scene, 0.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                       Eigen::Vector3d::UnitZ(), plain(0.0), rng);
    ASSERT_TRUE(r.valid);
    if (r.range_m < 11.5 + 1e-9) {
      ++in_crown;
      min_r = std::min(min_r, r.range_m);
      max_r = std::max(max_r, r.range_m);
    } else {
      EXPECT_NEAR(r.range_m, 20.0, 1e-9);
      ++behind;
    }
  }
  // P(pass 3 m of crown with a 1 m free path) = e^-3 = 5 %.
  EXPECT_NEAR(behind / 4000.0, std::exp(-3.0), 0.015);
  EXPECT_LT(min_r, 8.6);
  EXPECT_GT(max_r, 11.0);
  EXPECT_GE(min_r, 8.5);
}

// A pedestrian crossing the beam is seen while it is on the ray and not before or after; the
// position follows its walk back and forth.
TEST(LidarReturn, MovingObjectsAreSeenAtTheFiringTime) {
  MovingObject person;
  person.shape = MovingObject::Shape::kCylinder;
  person.half = Eigen::Vector3d(0.25, 0.25, 1.75);
  person.start = Eigen::Vector3d(6.0, -3.0, -1.0);
  person.velocity = Eigen::Vector3d(0.0, 1.5, 0.0);
  person.pace_m = 6.0;
  const MovingObjects movers({person});
  const World w = wall(20.0, 0.5F);
  // y(t) = -3 + 1.5 t on the way out (0..4 s), back after.
  EXPECT_NEAR(movers.position(0, 2.0).y(), 0.0, 1e-12);
  EXPECT_NEAR(movers.position(0, 6.0).y(), 0.0, 1e-12);  // 4 s out, 2 s back
  EXPECT_NEAR(fire(w, Eigen::Vector3d::UnitX(), plain(0.0), 1, &movers, 2.0).mean, 5.75, 1e-9);
  EXPECT_NEAR(fire(w, Eigen::Vector3d::UnitX(), plain(0.0), 1, &movers, 0.0).mean, 20.0, 1e-9);
  EXPECT_NEAR(fire(w, Eigen::Vector3d::UnitX(), plain(0.0), 1, &movers, 6.0).mean, 5.75, 1e-9);
}

TEST(MovingObjects, NamedWorldsGetTrafficAndPeople) {
  const MovingObjects street =
      make_moving_objects(WorldKind::kStreet, SceneContent{3.0, 1.5, true}, 1, 400.0);
  int cars = 0, people = 0;
  for (const auto& o : street.objects()) {
    (o.shape == MovingObject::Shape::kBox ? cars : people)++;
  }
  EXPECT_EQ(people, 12);
  EXPECT_EQ(cars, 6);
  // Cars stay on the street, wrapping around.
  for (std::size_t i = 0; i < street.objects().size(); ++i) {
    for (double t = 0.0; t < 100.0; t += 7.0) {
      const Eigen::Vector3d p = street.position(i, t);
      EXPECT_GE(p.x(), -20.0 - 50.0);
      EXPECT_LE(p.x(), 380.0 + 50.0);
      EXPECT_LE(std::abs(p.y()), 10.0);
    }
  }
  EXPECT_TRUE(
      make_moving_objects(WorldKind::kCorridor, SceneContent{3.0, 1.5, true}, 1, 400.0).empty());
  EXPECT_EQ(
      make_moving_objects(WorldKind::kRoom, SceneContent{2.0, 0.0, true}, 1, 0.0).objects().size(),
      2U);
}

}  // namespace
}  // namespace livod::sim

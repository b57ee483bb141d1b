// The renderer's speed-ups change no result: the SAH tree with front-to-back, two-lane traversal
// finds exactly the brute-force nearest hit (also for rays from inside world-sized slabs and rays
// parallel to the axes, where the slab test meets 0 * inf), the cached texture lookup returns the
// uncached value bit for bit, and a rendered frame equals ideal_intensity() pixel by pixel.

#include <gtest/gtest.h>

#include <random>

#include "tools/sim/camera_sim.hpp"
#include "tools/sim/world.hpp"
#include "tools/sim/worlds.hpp"

namespace livod::sim {
namespace {

// A room-like world: six world-sized slabs around the origin plus random boxes (axis-aligned and
// rotated), cylinders and spheres inside. `singles` holds each primitive in a world of its own.
World room_like(std::vector<World>& singles, std::mt19937& rng) {
  World world;
  const auto add_box = [&](const Eigen::Vector3d& c, const Eigen::Vector3d& h, double yaw) {
    world.add_box(c, h, yaw, Surface{});
    singles.emplace_back().add_box(c, h, yaw, Surface{});
  };
  add_box({0, 0, -0.1}, {20.1, 15.1, 0.1}, 0.0);
  add_box({0, 0, 6.1}, {20.1, 15.1, 0.1}, 0.0);
  add_box({20.1, 0, 3}, {0.1, 15.1, 3}, 0.0);
  add_box({-20.1, 0, 3}, {0.1, 15.1, 3}, 0.0);
  add_box({0, 15.1, 3}, {20.1, 0.1, 3}, 0.0);
  add_box({0, -15.1, 3}, {20.1, 0.1, 3}, 0.0);
  std::uniform_real_distribution<double> x(-18.0, 18.0);
  std::uniform_real_distribution<double> y(-13.0, 13.0);
  std::uniform_real_distribution<double> z(0.0, 5.0);
  std::uniform_real_distribution<double> size(0.1, 1.5);
  std::uniform_int_distribution<int> kind(0, 3);
  for (int i = 0; i < 150; ++i) {
    const Eigen::Vector3d c(x(rng), y(rng), z(rng));
    switch (kind(rng)) {
      case 0:
        add_box(c, {size(rng), size(rng), size(rng)}, 0.0);
        break;
      case 1:
        add_box(c, {size(rng), size(rng), size(rng)}, x(rng));
        break;
      case 2: {
        const double r = 0.3 * size(rng);
        const double h = 3.0 * size(rng);
        world.add_cylinder(c, r, h, Surface{});
        singles.emplace_back().add_cylinder(c, r, h, Surface{});
        break;
      }
      default: {
        const double r = size(rng);
        world.add_sphere(c, r, Surface{});
        singles.emplace_back().add_sphere(c, r, Surface{});
        break;
      }
    }
  }
  world.build();
  for (auto& s : singles) s.build();
  return world;
}

TEST(RenderSpeedups, TraversalFindsTheBruteForceNearestHit) {
  std::mt19937 rng(3);
  std::vector<World> singles;
  const World world = room_like(singles, rng);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> inside(-10.0, 10.0);
  int rays = 0;
  int axis_parallel = 0;
  for (int r = 0; r < 3000; ++r) {
    const Eigen::Vector3d origin(inside(rng), 0.6 * inside(rng), 2.5 + 0.2 * inside(rng));
    Eigen::Vector3d dir = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    if (r % 10 == 0) {
      // Exactly along an axis: the other components are +-0, their inverses +-inf.
      dir = Eigen::Vector3d::Zero();
      dir[r / 10 % 3] = (r / 30) % 2 == 0 ? 1.0 : -1.0;
      ++axis_parallel;
    }
    Hit hit;
    const bool found = world.intersect(origin, dir, 1e-3, 100.0, hit);
    double best = 1e300;
    for (const auto& s : singles) {
      Hit h;
      if (s.intersect(origin, dir, 1e-3, 100.0, h)) best = std::min(best, h.range);
    }
    ASSERT_EQ(found, best < 1e300) << "ray " << r;
    if (found) {
      ASSERT_EQ(hit.range, best) << "ray " << r;  // the same primitive test, so bit-exact
      EXPECT_EQ(hit.point, origin + hit.range * dir);
    }
    ++rays;
  }
  EXPECT_EQ(rays, 3000);
  EXPECT_EQ(axis_parallel, 300);
}

TEST(RenderSpeedups, CachedAlbedoIsBitIdentical) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> coord(-30.0, 30.0);
  std::uniform_real_distribution<double> step(-0.02, 0.02);
  Surface a;
  a.texture_scale = 2.0F;
  a.texture_seed = 7;
  Surface b;
  b.texture_scale = 5.0F;
  b.texture_seed = 70;
  b.texture_contrast = 0.5F;
  AlbedoCache cache;
  Eigen::Vector3d p(coord(rng), coord(rng), coord(rng));
  for (int i = 0; i < 20000; ++i) {
    // Mostly small steps (neighbouring pixels, cache hits), sometimes a jump or another surface.
    p = i % 50 == 0 ? Eigen::Vector3d(coord(rng), coord(rng), coord(rng))
                    : Eigen::Vector3d(p + Eigen::Vector3d(step(rng), step(rng), step(rng)));
    const Surface& s = i % 7 == 0 ? b : a;
    ASSERT_EQ(World::albedo(s, p, cache), World::albedo(s, p)) << i;
  }
}

TEST(RenderSpeedups, RenderedFrameEqualsIdealIntensityPerPixel) {
  const World world = make_room_world(2);
  CameraSimParams params;
  auto& k = params.intrinsics;
  k.model = CameraIntrinsics::Model::kPinholeRadtan;
  k.width = 200;
  k.height = 150;
  k.fx = 120.0;
  k.fy = 120.0;
  k.cx = 99.5;
  k.cy = 74.5;
  k.distortion = {-0.07, 0.11, -0.001, 0.0003};
  params.noise_sigma = 0.0;
  const CameraSim cam(params);
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  T_world_cam.linear() = (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) *
                          Eigen::AngleAxisd(-1.7, Eigen::Vector3d::UnitX()))
                             .toRotationMatrix();
  T_world_cam.translation() = Eigen::Vector3d(0.4, -0.3, 1.3);
  std::mt19937_64 rng(1);
  GreyImage img;
  cam.render(world, T_world_cam, 0.0045, rng, img);
  for (int y = 0; y < k.height; ++y) {
    for (int x = 0; x < k.width; ++x) {
      const double v = cam.ideal_intensity(world, T_world_cam, 0.0045, x, y);
      ASSERT_EQ(img.at(x, y), static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L)))
          << x << ", " << y;
    }
  }
}

}  // namespace
}  // namespace livod::sim

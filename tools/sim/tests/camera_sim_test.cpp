#include "tools/sim/camera_sim.hpp"

#include <gtest/gtest.h>

#include "tools/sim/trajectory.hpp"
#include "tools/sim/worlds.hpp"

namespace livod::sim {
namespace {

CameraSimParams small_camera(CameraIntrinsics::Model model) {
  CameraSimParams p;
  auto& k = p.intrinsics;
  k.model = model;
  k.width = 160;
  k.height = 128;
  k.fx = model == CameraIntrinsics::Model::kEquidistant ? 90.0 : 120.0;
  k.fy = k.fx;
  k.cx = 79.5;
  k.cy = 63.5;
  k.distortion = model == CameraIntrinsics::Model::kEquidistant
                     ? std::array<double, 4>{-0.03, -0.008, 0.008, -0.003}
                     : std::array<double, 4>{-0.08, 0.12, -0.001, 0.0003};
  p.noise_sigma = 0.0;
  return p;
}

// A world point rendered at pixel (x, y) projects back onto (x, y) with the ground-truth pose and
// the camera model: the renderer and the model agree, distortion included.
TEST(CameraSim, RenderedPointsReprojectOntoTheirPixels) {
  const World world = make_room_world(3);
  for (auto model :
       {CameraIntrinsics::Model::kPinholeRadtan, CameraIntrinsics::Model::kEquidistant}) {
    const CameraSim cam(small_camera(model));
    Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
    // Looking along +x from 1.5 m height: camera z = world x, camera x = -world y, y = -world z.
    T_world_cam.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
    T_world_cam.translation() = Eigen::Vector3d(0.5, 0.2, 1.5);
    int checked = 0;
    for (int y = 2; y < 128; y += 9) {
      for (int x = 3; x < 160; x += 11) {
        const auto ray = cam.model().unproject(Eigen::Vector2d(x, y));
        ASSERT_TRUE(ray);
        Hit hit;
        const Eigen::Vector3d dir = T_world_cam.linear() * *ray;
        ASSERT_TRUE(world.intersect(T_world_cam.translation(), dir, 1e-3, 100.0, hit));
        const Eigen::Vector3d p_cam = T_world_cam.inverse() * hit.point;
        const auto px = cam.model().project(p_cam);
        ASSERT_TRUE(px);
        EXPECT_LT((*px - Eigen::Vector2d(x, y)).norm(), 1e-6);
        ++checked;
      }
    }
    EXPECT_GT(checked, 100);
  }
}

TEST(CameraSim, ImagesAreTexturedAndScaleWithExposure) {
  const World world = make_room_world(3);
  const CameraSim cam(small_camera(CameraIntrinsics::Model::kPinholeRadtan));
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  T_world_cam.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  T_world_cam.translation() = Eigen::Vector3d(0.0, 0.0, 1.5);
  std::mt19937_64 rng(1);
  GreyImage a;
  GreyImage b;
  cam.render(world, T_world_cam, 0.002, rng, a);
  cam.render(world, T_world_cam, 0.004, rng, b);
  double sum_a = 0;
  double sum_b = 0;
  double grad = 0;
  for (int y = 0; y < 128; ++y) {
    for (int x = 0; x + 1 < 160; ++x) {
      sum_a += a.at(x, y);
      sum_b += b.at(x, y);
      grad += std::abs(b.at(x + 1, y) - b.at(x, y));
    }
  }
  EXPECT_NEAR(sum_b / sum_a, 2.0, 0.05);  // intensity is proportional to exposure
  EXPECT_GT(grad / (128 * 159), 1.0);     // mean horizontal gradient > 1 grey level per pixel
}

}  // namespace
}  // namespace livod::sim

#include "core/camera_model.hpp"

#include <gtest/gtest.h>

#include <random>

namespace livod {
namespace {

CameraIntrinsics pinhole() {
  // FAST-LIVO2's Avia rig camera at scale 0.5 (fast-livo2-notes.md 1.5).
  CameraIntrinsics k;
  k.model = CameraIntrinsics::Model::kPinholeRadtan;
  k.width = 1280;
  k.height = 1024;
  k.fx = 1293.57;
  k.fy = 1293.32;
  k.cx = 626.91;
  k.cy = 522.80;
  k.distortion = {-0.07616, 0.123001, -0.00113, 0.000251};
  return k.scaled(0.5);
}

CameraIntrinsics fisheye() {
  // The Hilti 2022 Alphasense camera (fast-livo2-notes.md 1.5).
  CameraIntrinsics k;
  k.model = CameraIntrinsics::Model::kEquidistant;
  k.width = 720;
  k.height = 540;
  k.fx = 351.31;
  k.fy = 351.49;
  k.cx = 367.85;
  k.cy = 253.84;
  k.distortion = {-0.0370, -0.0089, 0.0089, -0.0038};
  return k;
}

class CameraModelTest : public ::testing::TestWithParam<bool> {
 protected:
  CameraModel model() const { return CameraModel(GetParam() ? fisheye() : pinhole()); }
};

TEST_P(CameraModelTest, ProjectionJacobianMatchesFiniteDifferences) {
  const CameraModel cam = model();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int checked = 0;
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3d p(u(rng) * 3.0, u(rng) * 2.5, 0.5 + 4.0 * (u(rng) + 1.0));
    Eigen::Matrix<double, 2, 3> J;
    const auto px = cam.project(p, &J);
    if (!px || !cam.in_image(*px)) continue;
    Eigen::Matrix<double, 2, 3> J_fd;
    const double h = 1e-6;
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3d dp = Eigen::Vector3d::Zero();
      dp[c] = h;
      J_fd.col(c) = (*cam.project(p + dp) - *cam.project(p - dp)) / (2 * h);
    }
    EXPECT_LT((J - J_fd).norm(), 1e-4 * (1.0 + J.norm())) << "p = " << p.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

TEST_P(CameraModelTest, UnprojectInvertsProjectAcrossTheImage) {
  const CameraModel cam = model();
  const auto& k = cam.intrinsics();
  for (int y = 0; y < k.height; y += 37) {
    for (int x = 0; x < k.width; x += 41) {
      const Eigen::Vector2d px(x, y);
      const auto ray = cam.unproject(px);
      ASSERT_TRUE(ray.has_value()) << px.transpose();
      EXPECT_NEAR(ray->norm(), 1.0, 1e-12);
      const auto back = cam.project(*ray * 3.7);
      ASSERT_TRUE(back.has_value());
      EXPECT_LT((*back - px).norm(), 1e-6) << px.transpose();
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Models, CameraModelTest, ::testing::Values(false, true),
                         [](const auto& param_info) {
                           return param_info.param ? "Equidistant" : "Pinhole";
                         });

TEST(CameraModel, PinholeJacobianDiffersFromTheFisheyeOneAtTheEdge) {
  // FAST-LIVO2 uses the pinhole Jacobian for every model; for a fisheye at 60 deg off-axis the
  // true Jacobian is much smaller. This guards against regressing to that shortcut.
  const CameraModel cam(fisheye());
  const double angle = 60.0 * M_PI / 180.0;
  const Eigen::Vector3d p(std::sin(angle), 0.0, std::cos(angle));
  Eigen::Matrix<double, 2, 3> J;
  ASSERT_TRUE(cam.project(p, &J));
  const double pinhole_dudx = cam.intrinsics().fx / p.z();
  EXPECT_LT(std::abs(J(0, 0)), 0.6 * pinhole_dudx);
}

TEST(CameraModel, PointsBehindThePinholeCameraDoNotProject) {
  const CameraModel cam(pinhole());
  EXPECT_FALSE(cam.project(Eigen::Vector3d(0.1, 0.1, -1.0)).has_value());
  EXPECT_FALSE(cam.project(Eigen::Vector3d(0.1, 0.1, 0.0)).has_value());
}

TEST(CameraModel, ScalingKeepsPixelCentresConsistent) {
  CameraIntrinsics k = pinhole();
  const CameraIntrinsics half = k.scaled(0.5);
  EXPECT_EQ(half.width, k.width / 2);
  const CameraModel full(k);
  const CameraModel small(half);
  const Eigen::Vector3d p(0.3, -0.2, 2.0);
  const Eigen::Vector2d a = *full.project(p);
  const Eigen::Vector2d b = *small.project(p);
  EXPECT_NEAR((a.x() + 0.5) * 0.5 - 0.5, b.x(), 1e-9);
  EXPECT_NEAR((a.y() + 0.5) * 0.5 - 0.5, b.y(), 1e-9);
}

}  // namespace
}  // namespace livod

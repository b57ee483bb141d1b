// The plane-induced warp reproduces a synthetic plane's appearance: a textured plane is rendered
// (ray cast through the camera model, distortion included) from a reference camera and from a
// second camera moved, rolled and turned; reference patches taken from the first image and warped
// to the second view must match what the second image shows, at every pyramid level, far better
// than the unwarped patches do.

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>

#include "core/so3.hpp"
#include "estimator/vio/image_pyramid.hpp"
#include "estimator/vio/photometric.hpp"
#include "estimator/vio/reference_patch.hpp"
#include "estimator/vio/warp.hpp"

namespace livod::estimator::vio {
namespace {

struct PlaneScene {
  Eigen::Vector3d point{0.0, 0.0, 3.0};  // on the plane (world)
  Eigen::Vector3d normal = Eigen::Vector3d(0.25, -0.2, -1.0).normalized();
  Eigen::Vector3d u_axis;
  Eigen::Vector3d v_axis;
  PlaneScene() {
    u_axis = normal.cross(Eigen::Vector3d::UnitY()).normalized();
    v_axis = normal.cross(u_axis);
  }
  // Smooth texture in plane coordinates (m): periods of 6-12 cm.
  [[nodiscard]] double albedo(const Eigen::Vector3d& p) const {
    const double a = (p - point).dot(u_axis);
    const double b = (p - point).dot(v_axis);
    return 128.0 + 50.0 * std::sin(60.0 * a + 1.0) * std::cos(45.0 * b) +
           40.0 * std::sin(80.0 * b - 30.0 * a);
  }
};

cv::Mat render(const CameraModel& camera, const Eigen::Isometry3d& T_world_cam,
               const PlaneScene& scene) {
  const auto& k = camera.intrinsics();
  cv::Mat img(k.height, k.width, CV_8UC1, cv::Scalar(0));
  for (int y = 0; y < k.height; ++y) {
    for (int x = 0; x < k.width; ++x) {
      const auto ray = camera.unproject(Eigen::Vector2d(x, y));
      if (!ray) continue;
      const Eigen::Vector3d d = T_world_cam.linear() * *ray;
      const Eigen::Vector3d o = T_world_cam.translation();
      const double t = scene.normal.dot(scene.point - o) / scene.normal.dot(d);
      if (!(t > 0.0)) continue;
      img.at<std::uint8_t>(y, x) =
          static_cast<std::uint8_t>(std::clamp(std::lround(scene.albedo(o + t * d)), 0L, 255L));
    }
  }
  return img;
}

CameraIntrinsics camera_intrinsics() {
  CameraIntrinsics k;
  k.model = CameraIntrinsics::Model::kPinholeRadtan;
  k.width = 640;
  k.height = 512;
  k.fx = 500.0;
  k.fy = 500.0;
  k.cx = 313.2;
  k.cy = 261.1;
  k.distortion = {-0.07616, 0.123001, -0.00113, 0.000251};
  return k;
}

TEST(VioWarp, WarpedReferencePatchesMatchTheSecondView) {
  const CameraModel camera(camera_intrinsics());
  const PlaneScene scene;
  const Eigen::Isometry3d T_w_ref = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_w_cur = Eigen::Isometry3d::Identity();
  // Moved sideways and closer, rolled 25 deg and turned 12 deg: the patches scale, shear, rotate.
  T_w_cur.linear() = so3::exp(Eigen::Vector3d(0.0, -0.21, 0.44));
  T_w_cur.translation() = Eigen::Vector3d(0.6, 0.1, 0.9);
  constexpr int kLevels = 3;
  constexpr int kP = 8;
  ImagePyramid ref_pyr;
  ImagePyramid cur_pyr;
  ref_pyr.build(render(camera, T_w_ref, scene), kLevels);
  cur_pyr.build(render(camera, T_w_cur, scene), kLevels);
  const Eigen::Isometry3d T_cur_ref = T_w_cur.inverse() * T_w_ref;

  double warped_sq = 0.0;
  double plain_sq = 0.0;
  int samples = 0;
  int levels_used[kLevels] = {0, 0, 0};
  double level_sq[kLevels] = {0, 0, 0};
  for (int gy = -3; gy <= 3; ++gy) {
    for (int gx = -4; gx <= 4; ++gx) {
      // A point on the plane, seen by both cameras away from the borders.
      const Eigen::Vector3d p = scene.point + 0.18 * gx * scene.u_axis + 0.18 * gy * scene.v_axis;
      const auto px_ref = camera.project(T_w_ref.inverse() * p);
      const auto px_cur = camera.project(T_w_cur.inverse() * p);
      if (!px_ref || !px_cur || !camera.in_image(*px_ref, 40) || !camera.in_image(*px_cur, 40)) {
        continue;
      }
      PatchObservation obs;
      ASSERT_TRUE(capture_blocks(ref_pyr, *px_ref, kP, obs));
      obs.pixel = *px_ref;
      const Eigen::Vector3d p_ref = T_w_ref.inverse() * p;
      const Eigen::Vector3d n_ref = T_w_ref.linear().transpose() * scene.normal;
      const auto A = affine_warp(camera, T_cur_ref, p_ref, n_ref);
      ASSERT_TRUE(A);
      const Eigen::Matrix2d A_ref_cur = A->inverse();
      for (int l = 0; l < kLevels; ++l) {
        float warped[kP * kP];
        if (!warp_reference_patch(obs, A_ref_cur, l, kLevels, kP, warped)) continue;
        ++levels_used[l];
        // Unwarped: the reference block's patch at the same level, as it is.
        float plain[kP * kP];
        ASSERT_TRUE(warp_reference_patch(obs, Eigen::Matrix2d::Identity(), l, kLevels, kP, plain));
        PatchEval e_w;
        PatchEval e_p;
        ASSERT_TRUE(evaluate_patch(cur_pyr.level(l), l, kP, *px_cur, 1.0, warped, e_w));
        ASSERT_TRUE(evaluate_patch(cur_pyr.level(l), l, kP, *px_cur, 1.0, plain, e_p));
        for (int i = 0; i < kP * kP; ++i) {
          warped_sq += static_cast<double>(e_w.residual[i]) * e_w.residual[i];
          level_sq[l] += static_cast<double>(e_w.residual[i]) * e_w.residual[i];
          plain_sq += static_cast<double>(e_p.residual[i]) * e_p.residual[i];
        }
        samples += kP * kP;
      }
    }
  }
  ASSERT_GT(samples, 0);
  const double warped_rms = std::sqrt(warped_sq / samples);
  const double plain_rms = std::sqrt(plain_sq / samples);
  std::printf("[warp] %d pixels, RMS warped %.2f, unwarped %.2f grey levels; levels %d %d %d\n",
              samples, warped_rms, plain_rms, levels_used[0], levels_used[1], levels_used[2]);
  for (int l = 0; l < kLevels; ++l) {
    std::printf("[warp] level %d: RMS %.2f\n", l, std::sqrt(level_sq[l] / (64.0 * levels_used[l])));
    EXPECT_GT(levels_used[l], 10) << "level " << l;
  }
  // Level 0 is exact up to the rendering; coarser levels interpolate texture closer to their
  // Nyquist limit and compare reference and current levels whose blur differs by up to a factor
  // of sqrt(2) (the scale between the views is not a power of two).
  EXPECT_LT(std::sqrt(level_sq[0] / (64.0 * levels_used[0])), 1.0);
  EXPECT_LT(warped_rms, 6.0);
  EXPECT_GT(plain_rms, 4.0 * warped_rms);
}

TEST(VioWarp, AffineWarpIsTheDerivativeOfThePlaneHomography) {
  // Through the camera model, as finite differences: pixels around the reference pixel are
  // unprojected, intersected with the plane, moved and projected into the current camera.
  const CameraModel camera(camera_intrinsics());
  Eigen::Isometry3d T_cur_ref = Eigen::Isometry3d::Identity();
  T_cur_ref.linear() = so3::exp(Eigen::Vector3d(0.1, -0.3, 0.5));
  T_cur_ref.translation() = Eigen::Vector3d(-0.4, 0.2, -0.7);
  const Eigen::Vector3d n_ref = Eigen::Vector3d(0.3, -0.2, -1.0).normalized();
  int checked = 0;
  for (const double x : {-1.2, -0.4, 0.3, 1.1}) {
    for (const double y : {-0.9, 0.1, 0.8}) {
      const Eigen::Vector3d p_ref(x, y, 3.0);
      const auto px_ref = camera.project(p_ref);
      const auto A = affine_warp(camera, T_cur_ref, p_ref, n_ref);
      ASSERT_TRUE(px_ref && A);
      auto through_plane = [&](const Eigen::Vector2d& d) {
        const Eigen::Vector3d ray = *camera.unproject(*px_ref + d);
        return *camera.project(T_cur_ref * ((n_ref.dot(p_ref) / n_ref.dot(ray)) * ray));
      };
      const double h = 1e-3;
      Eigen::Matrix2d A_fd;
      A_fd.col(0) = (through_plane({h, 0}) - through_plane({-h, 0})) / (2 * h);
      A_fd.col(1) = (through_plane({0, h}) - through_plane({0, -h})) / (2 * h);
      EXPECT_LT((*A - A_fd).norm(), 1e-5 * A_fd.norm()) << "point " << p_ref.transpose();
      ++checked;
    }
  }
  EXPECT_EQ(checked, 12);
}

TEST(VioWarp, IdentityMotionGivesTheIdentityWarp) {
  const CameraModel camera(camera_intrinsics());
  const Eigen::Vector3d p(0.3, -0.2, 2.5);
  const auto px = camera.project(p);
  ASSERT_TRUE(px);
  const auto A = affine_warp(camera, Eigen::Isometry3d::Identity(), p,
                             Eigen::Vector3d(0.1, 0.2, -1.0).normalized());
  ASSERT_TRUE(A);
  EXPECT_LT((*A - Eigen::Matrix2d::Identity()).norm(), 1e-6);
  EXPECT_EQ(reference_level_offset(Eigen::Matrix2d::Identity()), 0);
  EXPECT_EQ(reference_level_offset(2.0 * Eigen::Matrix2d::Identity()), 1);
  EXPECT_EQ(reference_level_offset(0.25 * Eigen::Matrix2d::Identity()), -2);
}

}  // namespace
}  // namespace livod::estimator::vio

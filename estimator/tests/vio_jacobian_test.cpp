// The photometric update's Jacobians against finite differences, for both camera models:
//  - the pixel of a world point with respect to the pose error state (exact model Jacobian,
//    distortion included: FAST-LIVO2 uses the pinhole one for every model);
//  - the photometric residual of a patch with respect to rotation, position and inverse exposure
//    on a smooth 8-bit image (sampling and quantisation limit the agreement to a few percent).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <random>

#include "core/so3.hpp"
#include "estimator/vio/camera_projection.hpp"
#include "estimator/vio/image_pyramid.hpp"
#include "estimator/vio/photometric.hpp"

namespace livod::estimator::vio {
namespace {

CameraIntrinsics pinhole_k3() {
  // FAST-LIVO2's Avia rig camera at scale 0.5 with a sixth-order radial term added.
  CameraIntrinsics k;
  k.model = CameraIntrinsics::Model::kPinholeRadtan;
  k.width = 1280;
  k.height = 1024;
  k.fx = 1293.57;
  k.fy = 1293.32;
  k.cx = 626.91;
  k.cy = 522.80;
  k.distortion = {-0.07616, 0.123001, -0.00113, 0.000251};
  k.radtan_k3 = -0.02;
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

State random_state(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  State x;
  x.R_world_imu = so3::exp(Eigen::Vector3d(0.3 * u(rng), 0.3 * u(rng), 3.0 * u(rng)));
  x.p_world_imu = Eigen::Vector3d(2.0 * u(rng), 2.0 * u(rng), 0.5 * u(rng));
  x.inv_exposure = 1.0 + 0.3 * u(rng);
  return x;
}

// A forward-looking camera a little off the IMU (the simulator's rig layout).
CameraExtrinsic rig_extrinsic() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  T.translation() = Eigen::Vector3d(0.06, -0.02, 0.04);
  return CameraExtrinsic::from(T);
}

class VioJacobian : public ::testing::TestWithParam<bool> {
 protected:
  [[nodiscard]] CameraIntrinsics intrinsics() const {
    return GetParam() ? fisheye() : pinhole_k3();
  }
};

TEST_P(VioJacobian, PixelWithRespectToPoseMatchesFiniteDifferences) {
  const CameraModel camera(intrinsics());
  const CameraExtrinsic ext = rig_extrinsic();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int checked = 0;
  double worst_pinhole = 0.0;
  for (int trial = 0; trial < 400; ++trial) {
    const State x = random_state(rng);
    // A point in front of the camera, anywhere in the image (the edges are where a pinhole
    // Jacobian of a distorted lens is most wrong).
    const Eigen::Vector3d p_cam(2.0 * u(rng), 1.6 * u(rng), 1.0 + 2.0 * (u(rng) + 1.0));
    const Eigen::Vector3d p_world = ext.T_world_cam(x) * p_cam;
    PoseJacobian J;
    const auto px = project_from_state(camera, ext, x, p_world, &J);
    if (!px || !camera.in_image(*px)) continue;
    PoseJacobian J_fd;
    const double h = 1e-6;
    for (int c = 0; c < 6; ++c) {
      StateVector d = StateVector::Zero();
      d(c < 3 ? kRot + c : kPos + c - 3) = h;
      const auto plus = project_from_state(camera, ext, x.boxplus(d), p_world);
      const auto minus = project_from_state(camera, ext, x.boxplus(-d), p_world);
      ASSERT_TRUE(plus && minus);
      J_fd.col(c) = (*plus - *minus) / (2.0 * h);
    }
    EXPECT_LT((J - J_fd).norm(), 1e-5 * (1.0 + J.norm())) << "pixel " << px->transpose();
    // What FAST-LIVO2 uses for every model: the pinhole Jacobian fx/z.
    const auto& k = camera.intrinsics();
    Eigen::Matrix<double, 2, 3> J_pinhole;
    J_pinhole << k.fx / p_cam.z(), 0.0, -k.fx * p_cam.x() / (p_cam.z() * p_cam.z()), 0.0,
        k.fy / p_cam.z(), -k.fy * p_cam.y() / (p_cam.z() * p_cam.z());
    Eigen::Matrix<double, 2, 3> J_model;
    camera.project(p_cam, &J_model);
    worst_pinhole = std::max(worst_pinhole, (J_pinhole - J_model).norm() / J_model.norm());
    ++checked;
  }
  EXPECT_GT(checked, 200);
  // The check above can tell models apart: the pinhole formula is far off for the fisheye.
  if (GetParam()) {
    EXPECT_GT(worst_pinhole, 0.5);
  }
}

// A smooth 8-bit texture: two sinusoids of 50-70 px period, full contrast.
cv::Mat smooth_image(int width, int height) {
  cv::Mat img(height, width, CV_8UC1);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double v =
          128.0 + 60.0 * std::sin(0.11 * x + 0.03 * y) + 55.0 * std::cos(0.09 * y - 0.05 * x + 0.7);
      img.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
    }
  }
  return img;
}

TEST_P(VioJacobian, PhotometricResidualMatchesFiniteDifferences) {
  const CameraIntrinsics k = intrinsics();
  const CameraModel camera(k);
  const CameraExtrinsic ext = rig_extrinsic();
  ImagePyramid pyramid;
  pyramid.build(smooth_image(k.width, k.height), 3);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  constexpr int kP = 8;
  std::vector<float> ref(kP * kP);
  for (auto& r : ref) r = static_cast<float>(120.0 + 20.0 * u(rng));
  int checked = 0;
  std::vector<double> errors;
  for (int trial = 0; trial < 60; ++trial) {
    const int level = trial % 3;
    const State x = random_state(rng);
    const Eigen::Vector3d p_cam(1.2 * u(rng), 1.0 * u(rng), 2.5 + u(rng));
    const Eigen::Vector3d p_world = ext.T_world_cam(x) * p_cam;
    PoseJacobian J;
    const auto px = project_from_state(camera, ext, x, p_world, &J);
    if (!px || !camera.in_image(*px, 40.0)) continue;
    PatchEval e;
    ASSERT_TRUE(
        evaluate_patch(pyramid.level(level), level, kP, *px, x.inv_exposure, ref.data(), e));
    const Eigen::MatrixXd H = patch_jacobian(e, J);
    // Finite differences with steps that move the point by about one level pixel each way: the
    // bilinear image of quantised pixels is piecewise linear, so much smaller steps see one
    // pixel cell and its quantisation; a secant over two pixels is what the central-difference
    // gradient approximates too.
    const double pixel_per_unit = std::max(1.0, J.norm());
    Eigen::MatrixXd H_fd(kP * kP, 7);
    for (int c = 0; c < 7; ++c) {
      const int index = c < 3 ? kRot + c : c < 6 ? kPos + c - 3 : kExpo;
      const double h = c < 6 ? std::ldexp(1.0, level) / pixel_per_unit : 1e-3;
      StateVector d = StateVector::Zero();
      d(index) = h;
      PatchEval ep;
      PatchEval em;
      const State xp = x.boxplus(d);
      const State xm = x.boxplus(-d);
      ASSERT_TRUE(evaluate_patch(pyramid.level(level), level, kP,
                                 *project_from_state(camera, ext, xp, p_world), xp.inv_exposure,
                                 ref.data(), ep));
      ASSERT_TRUE(evaluate_patch(pyramid.level(level), level, kP,
                                 *project_from_state(camera, ext, xm, p_world), xm.inv_exposure,
                                 ref.data(), em));
      for (int i = 0; i < kP * kP; ++i) {
        H_fd(i, c) = (static_cast<double>(ep.residual[i]) - em.residual[i]) / (2.0 * h);
      }
    }
    const double pose_error =
        (H.leftCols<6>() - H_fd.leftCols<6>()).norm() / H_fd.leftCols<6>().norm();
    errors.push_back(pose_error);
    EXPECT_LT((H.col(6) - H_fd.col(6)).norm(), 1e-3 * H.col(6).norm());
    ++checked;
  }
  EXPECT_GT(checked, 20);
  std::sort(errors.begin(), errors.end());
  const double median = errors[errors.size() / 2];
  std::printf("[jacobian] photometric pose columns vs finite differences: median %.3f, max %.3f\n",
              median, errors.back());
  // Pose columns: a few percent (sampling of the quantised image); exposure column: exact.
  EXPECT_LT(median, 0.04);
  EXPECT_LT(errors.back(), 0.12);
}

TEST_P(VioJacobian, PatchNormalEquationsEqualTheRowSums) {
  const CameraIntrinsics k = intrinsics();
  const CameraModel camera(k);
  const CameraExtrinsic ext = rig_extrinsic();
  ImagePyramid pyramid;
  pyramid.build(smooth_image(k.width, k.height), 2);
  std::mt19937 rng(9);
  const State x = random_state(rng);
  const Eigen::Vector3d p_world = ext.T_world_cam(x) * Eigen::Vector3d(0.2, -0.1, 3.0);
  PoseJacobian J;
  const auto px = project_from_state(camera, ext, x, p_world, &J);
  ASSERT_TRUE(px);
  std::vector<float> ref(64, 100.0F);
  PatchEval e;
  ASSERT_TRUE(evaluate_patch(pyramid.level(1), 1, 8, *px, x.inv_exposure, ref.data(), e));
  const Eigen::MatrixXd H = patch_jacobian(e, J);
  Eigen::VectorXd r(64);
  for (int i = 0; i < 64; ++i) r(i) = e.residual[i];
  PatchNormals n;
  accumulate_patch(e, J, 0.0, true, n);  // no kernel: plain sums
  EXPECT_LT((n.HtWH - H.transpose() * H).norm(), 1e-6 * n.HtWH.norm());
  EXPECT_LT((n.HtWr - H.transpose() * r).norm(), 1e-6 * n.HtWr.norm());
  EXPECT_NEAR(n.cost, r.squaredNorm(), 1e-6 * n.cost);
  // With the kernel, pixels beyond it weigh huber / |r|.
  PatchNormals robust;
  const double huber = 5.0;
  accumulate_patch(e, J, huber, true, robust);
  Eigen::VectorXd w(64);
  for (int i = 0; i < 64; ++i) w(i) = std::abs(r(i)) > huber ? huber / std::abs(r(i)) : 1.0;
  EXPECT_LT((robust.HtWH - H.transpose() * w.asDiagonal() * H).norm(), 1e-6 * robust.HtWH.norm());
}

INSTANTIATE_TEST_SUITE_P(CameraModels, VioJacobian, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& param) {
                           return param.param ? std::string("Equidistant")
                                              : std::string("PinholeRadtan");
                         });

TEST(ImagePyramid, LevelPixelsSitAtPowersOfTwoOfLevelZero) {
  cv::Mat img(256, 320, CV_8UC1, cv::Scalar(10));
  img.at<std::uint8_t>(100, 200) = 255;  // row 100, column 200
  ImagePyramid pyramid;
  pyramid.build(img, 3);
  ASSERT_EQ(pyramid.levels(), 3);
  for (int l = 1; l < 3; ++l) {
    cv::Point at;
    cv::minMaxLoc(pyramid.level(l), nullptr, nullptr, nullptr, &at);
    const Eigen::Vector2d expected = ImagePyramid::to_level({200.0, 100.0}, l);
    EXPECT_EQ(at.x, static_cast<int>(expected.x())) << "level " << l;
    EXPECT_EQ(at.y, static_cast<int>(expected.y())) << "level " << l;
  }
  // Level-1 pixel x sits at level-0 pixel 2x, not 2x + 0.5: a dot at the odd column 201 is
  // equally far from the centres of level-1 pixels 100 and 101.
  cv::Mat odd(256, 320, CV_8UC1, cv::Scalar(10));
  odd.at<std::uint8_t>(100, 201) = 255;
  ImagePyramid odd_pyramid;
  odd_pyramid.build(odd, 2);
  EXPECT_EQ(odd_pyramid.level(1).at<std::uint8_t>(50, 100),
            odd_pyramid.level(1).at<std::uint8_t>(50, 101));
  EXPECT_GT(odd_pyramid.level(1).at<std::uint8_t>(50, 100), 20);
  // A real pyramid: the dot is spread by the Gaussian, not sampled with a stride (which would
  // keep it at 255 or lose it).
  double max1 = 0.0;
  cv::minMaxLoc(pyramid.level(1), nullptr, &max1);
  EXPECT_LT(max1, 100.0);
  EXPECT_GT(max1, 10.0);
}

}  // namespace
}  // namespace livod::estimator::vio

#pragma once
// The photometric residual of one patch at one pyramid level, and its linearisation on the
// filter's error state (fast-livo2-notes.md 1.4 step 5):
//
//   r_k = tau I_l(u / 2^l + o_k) - ref_k           k over the patch's P x P pixels
//
// u is the point's level-0 pixel (camera_projection.hpp), o_k the pixel offsets of the patch
// (centred: -(P-1)/2 ... (P-1)/2), tau the current inverse exposure and ref_k the warped
// reference patch already multiplied by the reference's inverse exposure. With g_k = d r_k / d u
// = tau grad I_l / 2^l (the central-difference gradient of the level), the error-state row is
//
//   H_k = [ g_k^T J_pose , I_l(u / 2^l + o_k) ]      over (dtheta, dp, dtau), state indices 0-6
//
// (J_pose = d u / d (dtheta, dp), shared by the patch's pixels). Every pixel's row has the
// same J_pose, so the 7x7 normal equations of a patch are built from 2x2 sums over its pixels.

#include <Eigen/Core>
#include <array>
#include <opencv2/core/mat.hpp>

#include "estimator/vio/camera_projection.hpp"

namespace livod::estimator::vio {

inline constexpr int kMaxPatchSize = 16;
inline constexpr int kMaxPatchPixels = kMaxPatchSize * kMaxPatchSize;

// Per pixel of one patch at one level, at a linearisation point.
struct PatchEval {
  int pixels = 0;
  std::array<float, kMaxPatchPixels> residual{};   // r_k
  std::array<float, kMaxPatchPixels> intensity{};  // I_l at the pixel (d r_k / d tau)
  std::array<float, kMaxPatchPixels> grad_x{};     // d r_k / d u (level-0 pixels)
  std::array<float, kMaxPatchPixels> grad_y{};
};

// Samples the patch around level-0 pixel `px` at `level` and fills `out`. `ref` holds P x P
// values (row-major) or is nullptr (residual = tau I). False when the patch (with the one-pixel
// border its gradients need) is not inside the level.
bool evaluate_patch(const cv::Mat& level_image, int level, int patch_size,
                    const Eigen::Vector2d& px, double tau, const float* ref, PatchEval& out);

// The weighted normal equations of one patch over (dtheta, dp, dtau): sum w H^T H and
// sum w H^T r, with Huber weights w at `huber` grey levels (<= 0: no kernel). `exposure`: false
// leaves the tau column out.
struct PatchNormals {
  Eigen::Matrix<double, 7, 7> HtWH = Eigen::Matrix<double, 7, 7>::Zero();
  Eigen::Matrix<double, 7, 1> HtWr = Eigen::Matrix<double, 7, 1>::Zero();
  double cost = 0.0;      // sum of the Huber costs rho(r) (= r^2 inside the kernel)
  double sq_error = 0.0;  // sum r^2
  int pixels = 0;
};
void accumulate_patch(const PatchEval& e, const PoseJacobian& J_pose, double huber, bool exposure,
                      PatchNormals& out);

// The rows H_k explicitly (pixels x 7), for tests and diagnostics.
Eigen::Matrix<double, Eigen::Dynamic, 7> patch_jacobian(const PatchEval& e,
                                                        const PoseJacobian& J_pose);

// Shi-Tomasi score of the P x P integer-pixel window centred on `px` (level 0): the smallest
// eigenvalue of the mean structure tensor (grey levels^2 / px^2). Negative when out of the image.
double shi_tomasi_score(const cv::Mat& image, const Eigen::Vector2d& px, int patch_size);

}  // namespace livod::estimator::vio

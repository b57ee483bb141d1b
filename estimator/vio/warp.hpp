#pragma once
// How a reference patch looks from the current camera: the plane-induced homography of the
// point's surface (FAST-LIVO2 normal_en; H = R_cr ((n^T p) I - t n^T) for pinhole cameras),
// linearised around the point into a 2x2 affine map of pixel offsets.
//
// The homography is evaluated through the actual camera model, distortion included: pixels
// around the reference pixel are unprojected, intersected with the plane, moved into the current
// camera and projected, and the affine map is their central difference. A pinhole formula would
// be wrong near the edge of a distorted or fisheye image.

#include <Eigen/Geometry>
#include <optional>

#include "core/camera_model.hpp"

namespace livod::estimator::vio {

// A_cur_ref: level-0 pixel offsets around px_ref in the reference image -> offsets around the
// point's pixel in the current image. p_ref: the point in the reference camera frame; n_ref: the
// surface normal in that frame (unit). T_cur_ref: reference camera -> current camera. `half`:
// the finite-difference half width in pixels (the patch half size). nullopt when the plane is
// seen edge-on or a pixel cannot be (un)projected.
std::optional<Eigen::Matrix2d> affine_warp(const CameraModel& camera,
                                           const Eigen::Isometry3d& T_cur_ref,
                                           const Eigen::Vector2d& px_ref,
                                           const Eigen::Vector3d& p_ref,
                                           const Eigen::Vector3d& n_ref, double half = 4.0);

// The search level of a warp: how many pyramid levels finer the reference is than the current
// view around the point (log2 of the linear scale of A_ref_cur, rounded), as an offset to add to
// the current level to get the reference level that matches it best.
int reference_level_offset(const Eigen::Matrix2d& A_ref_cur);

}  // namespace livod::estimator::vio

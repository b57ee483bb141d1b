#pragma once
// How a reference patch looks from the current camera: the plane-induced homography of the
// point's surface (FAST-LIVO2 normal_en; H = R_cr ((n^T p) I - t n^T) for pinhole cameras),
// linearised around the point into a 2x2 affine map of pixel offsets.
//
// The map is the exact derivative of the homography at the point through the actual camera model,
// distortion included: with B a basis of the plane's tangent directions, a small step B ds on the
// surface moves the point by J_ref B ds in the reference image and by J_cur R_cur_ref B ds in the
// current one (J: the model's projection Jacobians), so A_cur_ref = (J_cur R_cur_ref B)(J_ref
// B)^-1. A pinhole formula would be wrong near the edge of a distorted or fisheye image.

#include <Eigen/Geometry>
#include <optional>

#include "core/camera_model.hpp"

namespace livod::estimator::vio {

// A_cur_ref: level-0 pixel offsets around the point's pixel in the reference image -> offsets
// around its pixel in the current image. p_ref: the point in the reference camera frame; n_ref:
// the surface normal in that frame (unit). T_cur_ref: reference camera -> current camera. nullopt
// when the point is behind either camera or the plane is seen edge-on.
std::optional<Eigen::Matrix2d> affine_warp(const CameraModel& camera,
                                           const Eigen::Isometry3d& T_cur_ref,
                                           const Eigen::Vector3d& p_ref,
                                           const Eigen::Vector3d& n_ref);

// The search level of a warp: how many pyramid levels finer the reference is than the current
// view around the point (log2 of the linear scale of A_ref_cur, rounded), as an offset to add to
// the current level to get the reference level that matches it best.
int reference_level_offset(const Eigen::Matrix2d& A_ref_cur);

}  // namespace livod::estimator::vio

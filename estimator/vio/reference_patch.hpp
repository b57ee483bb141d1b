#pragma once
// Reference patches: taking one from an image (every pyramid level's block around the point) and
// seeing it from another camera (the block sampled through the affine warp of warp.hpp).

#include <Eigen/Core>

#include "estimator/vio/image_pyramid.hpp"
#include "estimator/vio/visual_map.hpp"

namespace livod::estimator::vio {

// Copies the blocks of every level around level-0 pixel `px` into obs.blocks / obs.block_pos (the
// pose, pixel and exposure fields are the caller's). False when a block leaves its level.
bool capture_blocks(const ImagePyramid& pyramid, const Eigen::Vector2d& px, int patch_size,
                    PatchObservation& obs);

// The reference patch as the current camera sees it at current pyramid level `level`: P x P
// values (row-major, centred offsets, times the reference's inverse exposure) sampled from the
// reference block whose scale matches best. A_ref_cur maps level-0 pixel offsets in the current
// image to level-0 offsets in the reference image. False when the warped patch leaves the block
// (a large rotation or scale change: the level is then not used) or patch_size > kMaxPatchSize.
bool warp_reference_patch(const PatchObservation& ref, const Eigen::Matrix2d& A_ref_cur, int level,
                          int levels, int patch_size, float* out);

}  // namespace livod::estimator::vio

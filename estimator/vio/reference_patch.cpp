#include "estimator/vio/reference_patch.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "estimator/vio/photometric.hpp"
#include "estimator/vio/warp.hpp"

namespace livod::estimator::vio {

bool capture_blocks(const ImagePyramid& pyramid, const Eigen::Vector2d& px, int patch_size,
                    PatchObservation& obs) {
  const int L = pyramid.levels();
  const int S = block_edge(patch_size);
  obs.blocks.resize(static_cast<std::size_t>(L * S * S));
  for (int l = 0; l < L; ++l) {
    const cv::Mat& img = pyramid.level(l);
    const Eigen::Vector2d u = ImagePyramid::to_level(px, l);
    // The point sits in the block's centre pixel pair: [S/2 - 1, S/2) from its top-left corner.
    const int tlx = static_cast<int>(std::floor(u.x())) - (S / 2 - 1);
    const int tly = static_cast<int>(std::floor(u.y())) - (S / 2 - 1);
    if (tlx < 0 || tly < 0 || tlx + S > img.cols || tly + S > img.rows) return false;
    std::uint8_t* dst = obs.blocks.data() + static_cast<std::size_t>(l * S * S);
    for (int y = 0; y < S; ++y) {
      const std::uint8_t* row = img.ptr<std::uint8_t>(tly + y) + tlx;
      std::copy(row, row + S, dst + y * S);
    }
    obs.block_pos[static_cast<std::size_t>(l)] =
        Eigen::Vector2f(static_cast<float>(u.x() - tlx), static_cast<float>(u.y() - tly));
  }
  return true;
}

bool warp_reference_patch(const PatchObservation& ref, const Eigen::Matrix2d& A_ref_cur, int level,
                          int levels, int patch_size, float* out) {
  const int P = patch_size;
  if (P > kMaxPatchSize) return false;  // as everywhere in the update (PatchEval)
  const int S = block_edge(P);
  const int k = std::clamp(level + reference_level_offset(A_ref_cur), 0, levels - 1);
  // Current level-l offsets -> reference level-k offsets.
  const Eigen::Matrix2d M = A_ref_cur * std::ldexp(1.0, level - k);
  const Eigen::Vector2d base = ref.block_pos[static_cast<std::size_t>(k)].cast<double>();
  const std::uint8_t* block = ref.block(k, S);
  // The warped patch is the affine image of a square: inside the block when its four corners are.
  const double c = 0.5 * static_cast<double>(P - 1);
  const auto limit = static_cast<double>(S - 1);
  for (const double cx : {-c, c}) {
    for (const double cy : {-c, c}) {
      const Eigen::Vector2d corner = base + M * Eigen::Vector2d(cx, cy);
      if (!(corner.x() >= 0.0 && corner.y() >= 0.0 && corner.x() < limit && corner.y() < limit)) {
        return false;
      }
    }
  }
  // The block as floats once (S^2 conversions instead of 4 per sample; the same values).
  std::array<float, block_edge(kMaxPatchSize) * block_edge(kMaxPatchSize)> pixels;  // NOLINT
  for (int q = 0; q < S * S; ++q) pixels[static_cast<std::size_t>(q)] = block[q];
  const auto tau = ref.inv_exposure;
  const Eigen::Vector2f step_x = M.col(0).cast<float>();
  const Eigen::Vector2f step_y = M.col(1).cast<float>();
  Eigen::Vector2f row = (base + M * Eigen::Vector2d(-c, -c)).cast<float>();
  for (int j = 0; j < P; ++j, row += step_y) {
    Eigen::Vector2f pos = row;
    for (int i = 0; i < P; ++i, pos += step_x) {
      // Float steps can drift a hair past a corner that lies exactly on the limit.
      const float x = std::clamp(pos.x(), 0.0F, static_cast<float>(limit) - 1e-4F);
      const float y = std::clamp(pos.y(), 0.0F, static_cast<float>(limit) - 1e-4F);
      out[j * P + i] = tau * sample_block(pixels.data(), S, x, y);
    }
  }
  return true;
}

}  // namespace livod::estimator::vio

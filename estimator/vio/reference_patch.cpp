#include "estimator/vio/reference_patch.hpp"

#include <algorithm>
#include <cmath>

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
  const int S = block_edge(P);
  const int k = std::clamp(level + reference_level_offset(A_ref_cur), 0, levels - 1);
  // Current level-l offsets -> reference level-k offsets.
  const Eigen::Matrix2d M = A_ref_cur * std::ldexp(1.0, level - k);
  const Eigen::Vector2d base = ref.block_pos[static_cast<std::size_t>(k)].cast<double>();
  const std::uint8_t* block = ref.block(k, S);
  const auto limit = static_cast<double>(S - 1);
  const double c = 0.5 * static_cast<double>(P - 1);
  const auto tau = ref.inv_exposure;
  for (int j = 0; j < P; ++j) {
    for (int i = 0; i < P; ++i) {
      const Eigen::Vector2d pos =
          base + M * Eigen::Vector2d(static_cast<double>(i) - c, static_cast<double>(j) - c);
      if (!(pos.x() >= 0.0 && pos.y() >= 0.0 && pos.x() < limit && pos.y() < limit)) return false;
      out[j * P + i] =
          tau * sample_block(block, S, static_cast<float>(pos.x()), static_cast<float>(pos.y()));
    }
  }
  return true;
}

}  // namespace livod::estimator::vio

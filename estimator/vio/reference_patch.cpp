#include "estimator/vio/reference_patch.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "estimator/vio/photometric.hpp"
#include "estimator/vio/warp.hpp"

namespace livod::estimator::vio {

namespace {

// warp_reference_patch's sampling for a patch edge known at compile time, four samples at a time
// in SIMD lanes (Eigen): the positions are stepped exactly as the scalar loop steps them, and
// every lane does the scalar loop's arithmetic (clamp, truncation, bilinear weights, the same
// products and sums in the same order), so the values are the same; only the four pixels of each
// sample are read one by one.
template <int kP>
void sample_warped_fixed(const std::uint8_t* block, const Eigen::Vector2f& start,
                         const Eigen::Vector2f& step_x, const Eigen::Vector2f& step_y, float hi,
                         float tau, float* out) {
  constexpr int kS = block_edge(kP);
  constexpr int kN = kP * kP;
  static_assert(kN % 4 == 0);
  std::array<float, kN> xs;  // NOLINT: every element is written below
  std::array<float, kN> ys;  // NOLINT
  Eigen::Vector2f row = start;
  for (int j = 0; j < kP; ++j, row += step_y) {
    Eigen::Vector2f pos = row;
    for (int i = 0; i < kP; ++i, pos += step_x) {
      xs[static_cast<std::size_t>(j * kP + i)] = pos.x();
      ys[static_cast<std::size_t>(j * kP + i)] = pos.y();
    }
  }
  using F = Eigen::Array4f;
  using I = Eigen::Array4i;
  for (int k = 0; k < kN; k += 4) {
    const F x = Eigen::Map<const F>(xs.data() + k).max(0.0F).min(hi);
    const F y = Eigen::Map<const F>(ys.data() + k).max(0.0F).min(hi);
    // Truncation is the floor for the non-negative positions here (as in sample_block).
    const I ix = x.cast<int>();
    const I iy = y.cast<int>();
    const F ax = x - ix.cast<float>();
    const F ay = y - iy.cast<float>();
    const I at = iy * kS + ix;
    // Built in registers: four scalar stores read back as one vector stall on store forwarding.
    const std::uint8_t* r0 = block + at[0];
    const std::uint8_t* r1 = block + at[1];
    const std::uint8_t* r2 = block + at[2];
    const std::uint8_t* r3 = block + at[3];
    const I p00(r0[0], r1[0], r2[0], r3[0]);
    const I p01(r0[1], r1[1], r2[1], r3[1]);
    const I p10(r0[kS], r1[kS], r2[kS], r3[kS]);
    const I p11(r0[kS + 1], r1[kS + 1], r2[kS + 1], r3[kS + 1]);
    const F bx = 1.0F - ax;
    const F v = (1.0F - ay) * (bx * p00.cast<float>() + ax * p01.cast<float>()) +
                ay * (bx * p10.cast<float>() + ax * p11.cast<float>());
    Eigen::Map<F>(out + k) = tau * v;
  }
}

}  // namespace

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
  const auto tau = ref.inv_exposure;
  const Eigen::Vector2f step_x = M.col(0).cast<float>();
  const Eigen::Vector2f step_y = M.col(1).cast<float>();
  const Eigen::Vector2f start = (base + M * Eigen::Vector2d(-c, -c)).cast<float>();
  // Float steps can drift a hair past a corner that lies exactly on the limit.
  const float hi = static_cast<float>(limit) - 1e-4F;
  if (P == 8) {
    sample_warped_fixed<8>(block, start, step_x, step_y, hi, tau, out);
    return true;
  }
  // The block as floats once (S^2 conversions instead of 4 per sample; the same values).
  std::array<float, block_edge(kMaxPatchSize) * block_edge(kMaxPatchSize)> pixels;  // NOLINT
  for (int q = 0; q < S * S; ++q) pixels[static_cast<std::size_t>(q)] = block[q];
  Eigen::Vector2f row = start;
  for (int j = 0; j < P; ++j, row += step_y) {
    Eigen::Vector2f pos = row;
    for (int i = 0; i < P; ++i, pos += step_x) {
      const float x = std::clamp(pos.x(), 0.0F, hi);
      const float y = std::clamp(pos.y(), 0.0F, hi);
      out[j * P + i] = tau * sample_block(pixels.data(), S, x, y);
    }
  }
  return true;
}

}  // namespace livod::estimator::vio

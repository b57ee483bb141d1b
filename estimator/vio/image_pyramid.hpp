#pragma once
// The image pyramid the photometric update runs on, and the pixel sampling it needs.
//
// A real pyramid: each level is the previous one low-pass filtered (5x5 Gaussian) and decimated by
// two (cv::pyrDown). FAST-LIVO2 samples coarse levels from the full image with a stride and no
// filtering (defect 10), which aliases texture finer than the stride.
//
// Coordinates: cv::pyrDown keeps the even pixels after filtering, so level-l pixel x_l sits at
// level-0 pixel x_0 = 2^l x_l exactly (pixel centres, x_0 = 0 is the centre of the first pixel).

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <opencv2/core/mat.hpp>
#include <vector>

namespace livod::estimator::vio {

class ImagePyramid {
 public:
  // `grey` (CV_8UC1) becomes level 0 (shared, not copied); levels 1.. are built from it.
  void build(const cv::Mat& grey, int levels);

  [[nodiscard]] int levels() const { return static_cast<int>(levels_.size()); }
  [[nodiscard]] const cv::Mat& level(int l) const { return levels_[static_cast<std::size_t>(l)]; }
  // Level-l position of a level-0 pixel position.
  [[nodiscard]] static Eigen::Vector2d to_level(const Eigen::Vector2d& px0, int l) {
    return px0 / static_cast<double>(1 << l);
  }

 private:
  std::vector<cv::Mat> levels_;
};

namespace detail {

// The integer corner of a sample grid and its bilinear weights; false when the n x n grid (and
// the row and column past it that bilinear sampling reads) is not inside the image.
struct GridWeights {
  int ix = 0;
  int iy = 0;
  float w00 = 0.0F;
  float w01 = 0.0F;
  float w10 = 0.0F;
  float w11 = 0.0F;
};
inline bool grid_weights(const cv::Mat& img, double x0, double y0, int n, GridWeights& g) {
  const double fx = std::floor(x0);
  const double fy = std::floor(y0);
  g.ix = static_cast<int>(fx);
  g.iy = static_cast<int>(fy);
  if (g.ix < 0 || g.iy < 0 || g.ix + n >= img.cols || g.iy + n >= img.rows) return false;
  const auto ax = static_cast<float>(x0 - fx);
  const auto ay = static_cast<float>(y0 - fy);
  g.w00 = (1.0F - ax) * (1.0F - ay);
  g.w01 = ax * (1.0F - ay);
  g.w10 = (1.0F - ax) * ay;
  g.w11 = ax * ay;
  return true;
}

}  // namespace detail

// sample_grid for a grid edge known at compile time (the 10 x 10 grid of an 8 x 8 patch and its
// gradient border), with the same arithmetic and so the same values. The rows are converted to
// float and the samples computed over widths rounded up to whole SIMD vectors (padding ignored),
// which the compiler vectorises at -O2 where it would not for a run-time edge.
template <int kN>
bool sample_grid_fixed(const cv::Mat& img, double x0, double y0, float* out) {
  detail::GridWeights g;
  if (!detail::grid_weights(img, x0, y0, kN, g)) return false;
  constexpr int kSamples = kN + 1;                  // image pixels read per row
  constexpr int kWide = (kN + 3) / 4 * 4;           // samples computed per row
  constexpr int kRow = (kWide + 1 + 15) / 16 * 16;  // floats kept per image row
  static_assert(kSamples <= kRow && kWide + 1 <= kRow);
  float rows[kSamples][kRow];  // NOLINT: every element read is written below
  const std::size_t step = img.step[0];
  const std::uint8_t* r = img.data + static_cast<std::size_t>(g.iy) * step + g.ix;
  // A whole vector of bytes per row where the image row holds them (one load); near the last
  // column only the kSamples bytes the grid needs (the rest is padding, never used). Copying
  // kSamples bytes into a zeroed buffer and reloading it as a vector stalls on store forwarding:
  // that was half the sampling time.
  const bool wide = g.ix + kRow <= img.cols;
  for (int j = 0; j < kSamples; ++j, r += step) {
    std::uint8_t bytes[kRow];  // NOLINT: written below, whole or in the part used
    if (wide) {
      std::memcpy(bytes, r, kRow);
    } else {
      std::memset(bytes, 0, kRow);
      std::memcpy(bytes, r, kSamples);
    }
    for (int i = 0; i < kRow; ++i) rows[j][i] = static_cast<float>(bytes[i]);
  }
  for (int j = 0; j < kN; ++j) {
    const float* upper = rows[j];
    const float* lower = rows[j + 1];
    float o[kWide];
    for (int i = 0; i < kWide; ++i) {
      o[i] = g.w00 * upper[i] + g.w01 * upper[i + 1] + g.w10 * lower[i] + g.w11 * lower[i + 1];
    }
    std::memcpy(out + j * kN, o, kN * sizeof(float));
  }
  return true;
}

// Bilinear samples of an 8-bit image on the n x n grid (x0 + i, y0 + j), i, j in [0, n), written
// row-major to `out`. All samples share one set of weights (the grid is integer-spaced), which is
// what makes patch sampling cheap. False (nothing written) when the grid is not inside the image.
inline bool sample_grid(const cv::Mat& img, double x0, double y0, int n, float* out) {
  if (n == 10) return sample_grid_fixed<10>(img, x0, y0, out);  // patch 8
  detail::GridWeights g;
  if (!detail::grid_weights(img, x0, y0, n, g)) return false;
  // Each image row is converted once and used by the two sample rows it borders.
  float upper[64];
  float lower[64];
  const bool small = n + 1 <= 64;
  const std::uint8_t* r = img.ptr<std::uint8_t>(g.iy) + g.ix;
  if (small) {
    for (int i = 0; i <= n; ++i) upper[i] = static_cast<float>(r[i]);
  }
  for (int j = 0; j < n; ++j) {
    const std::uint8_t* r0 = img.ptr<std::uint8_t>(g.iy + j) + g.ix;
    const std::uint8_t* r1 = img.ptr<std::uint8_t>(g.iy + j + 1) + g.ix;
    float* o = out + j * n;
    if (small) {
      for (int i = 0; i <= n; ++i) lower[i] = static_cast<float>(r1[i]);
      for (int i = 0; i < n; ++i) {
        o[i] = g.w00 * upper[i] + g.w01 * upper[i + 1] + g.w10 * lower[i] + g.w11 * lower[i + 1];
      }
      for (int i = 0; i <= n; ++i) upper[i] = lower[i];
    } else {
      for (int i = 0; i < n; ++i) {
        o[i] = g.w00 * static_cast<float>(r0[i]) + g.w01 * static_cast<float>(r0[i + 1]) +
               g.w10 * static_cast<float>(r1[i]) + g.w11 * static_cast<float>(r1[i + 1]);
      }
    }
  }
  return true;
}

// One bilinear sample of a row-major block of edge `stride` (8-bit pixels, or the same converted
// to float) at (x, y); the caller keeps (x, y) inside [0, stride - 1).
template <typename Pixel>
inline float sample_block(const Pixel* block, int stride, float x, float y) {
  // Truncation is the floor for the non-negative positions allowed here (and, unlike std::floor
  // without SSE4.1, no library call).
  const int ix = static_cast<int>(x);
  const int iy = static_cast<int>(y);
  const float ax = x - static_cast<float>(ix);
  const float ay = y - static_cast<float>(iy);
  const Pixel* r0 = block + iy * stride + ix;
  const Pixel* r1 = r0 + stride;
  return (1.0F - ay) * ((1.0F - ax) * static_cast<float>(r0[0]) + ax * static_cast<float>(r0[1])) +
         ay * ((1.0F - ax) * static_cast<float>(r1[0]) + ax * static_cast<float>(r1[1]));
}

}  // namespace livod::estimator::vio

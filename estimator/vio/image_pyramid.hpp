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

// Bilinear samples of an 8-bit image on the n x n grid (x0 + i, y0 + j), i, j in [0, n), written
// row-major to `out`. All samples share one set of weights (the grid is integer-spaced), which is
// what makes patch sampling cheap. False (nothing written) when the grid is not inside the image.
inline bool sample_grid(const cv::Mat& img, double x0, double y0, int n, float* out) {
  const double fx = std::floor(x0);
  const double fy = std::floor(y0);
  const int ix = static_cast<int>(fx);
  const int iy = static_cast<int>(fy);
  if (ix < 0 || iy < 0 || ix + n >= img.cols || iy + n >= img.rows) return false;
  const auto ax = static_cast<float>(x0 - fx);
  const auto ay = static_cast<float>(y0 - fy);
  const float w00 = (1.0F - ax) * (1.0F - ay);
  const float w01 = ax * (1.0F - ay);
  const float w10 = (1.0F - ax) * ay;
  const float w11 = ax * ay;
  // Each image row is converted once and used by the two sample rows it borders.
  float upper[64];
  float lower[64];
  const bool small = n + 1 <= 64;
  const std::uint8_t* r = img.ptr<std::uint8_t>(iy) + ix;
  if (small) {
    for (int i = 0; i <= n; ++i) upper[i] = static_cast<float>(r[i]);
  }
  for (int j = 0; j < n; ++j) {
    const std::uint8_t* r0 = img.ptr<std::uint8_t>(iy + j) + ix;
    const std::uint8_t* r1 = img.ptr<std::uint8_t>(iy + j + 1) + ix;
    float* o = out + j * n;
    if (small) {
      for (int i = 0; i <= n; ++i) lower[i] = static_cast<float>(r1[i]);
      for (int i = 0; i < n; ++i) {
        o[i] = w00 * upper[i] + w01 * upper[i + 1] + w10 * lower[i] + w11 * lower[i + 1];
      }
      for (int i = 0; i <= n; ++i) upper[i] = lower[i];
    } else {
      for (int i = 0; i < n; ++i) {
        o[i] = w00 * static_cast<float>(r0[i]) + w01 * static_cast<float>(r0[i + 1]) +
               w10 * static_cast<float>(r1[i]) + w11 * static_cast<float>(r1[i + 1]);
      }
    }
  }
  return true;
}

// One bilinear sample of a row-major 8-bit block of edge `stride` at (x, y); the caller keeps
// (x, y) inside [0, stride - 1).
inline float sample_block(const std::uint8_t* block, int stride, float x, float y) {
  // Truncation is the floor for the non-negative positions allowed here (and, unlike std::floor
  // without SSE4.1, no library call).
  const int ix = static_cast<int>(x);
  const int iy = static_cast<int>(y);
  const float ax = x - static_cast<float>(ix);
  const float ay = y - static_cast<float>(iy);
  const std::uint8_t* r0 = block + iy * stride + ix;
  const std::uint8_t* r1 = r0 + stride;
  return (1.0F - ay) * ((1.0F - ax) * static_cast<float>(r0[0]) + ax * static_cast<float>(r0[1])) +
         ay * ((1.0F - ax) * static_cast<float>(r1[0]) + ax * static_cast<float>(r1[1]));
}

}  // namespace livod::estimator::vio

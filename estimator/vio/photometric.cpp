#include "estimator/vio/photometric.hpp"

#include <cmath>
#include <cstdint>
#include <type_traits>

#include "estimator/vio/image_pyramid.hpp"

namespace livod::estimator::vio {

namespace {

// The per-pixel loop for any patch edge.
void fill_patch(const float* grid, int P, float t, float g, const float* ref, PatchEval& out) {
  const int G = P + 2;
  int k = 0;
  for (int j = 1; j <= P; ++j) {
    const float* row = grid + j * G;
    const float* up = row - G;
    const float* down = row + G;
    for (int i = 1; i <= P; ++i, ++k) {
      const float v = row[i];
      out.intensity[k] = v;
      out.residual[k] = t * v - ref[k];
      out.grad_x[k] = g * (row[i + 1] - row[i - 1]);
      out.grad_y[k] = g * (down[i] - up[i]);
    }
  }
}

// The same for an edge known at compile time, a row at a time in SIMD vectors (Eigen: the
// compiler does not vectorise the loop above at -O2, it cannot rule out aliasing), with the same
// arithmetic per pixel and so the same values.
template <int kP>
void fill_patch_fixed(const float* grid, float t, float g, const float* ref, PatchEval& out) {
  using Row = Eigen::Array<float, kP, 1>;
  using In = Eigen::Map<const Row>;
  using Out = Eigen::Map<Row>;
  constexpr int G = kP + 2;
  for (int j = 0; j < kP; ++j) {
    const float* row = grid + (j + 1) * G + 1;
    const int k = j * kP;
    const Row v = In(row);
    Out(out.intensity.data() + k) = v;
    Out(out.residual.data() + k) = t * v - In(ref + k);
    Out(out.grad_x.data() + k) = g * (In(row + 1) - In(row - 1));
    Out(out.grad_y.data() + k) = g * (In(row + G) - In(row - G));
  }
}

struct PixelSums {
  double gxx = 0, gxy = 0, gyy = 0, gxI = 0, gyI = 0, II = 0, gxr = 0, gyr = 0, Ir = 0;
  double cost = 0, sq = 0;
};

// One pixel's terms of the sums (the scalar form of pixel_sums, for its odd last pixel).
template <bool kExposure, bool kRobust>
void add_pixel(const PatchEval& e, int k, double huber, PixelSums& s) {
  const auto i = static_cast<std::size_t>(k);
  const double r = e.residual[i];
  const double r2 = r * r;
  double w = 1.0;
  if (kRobust && std::abs(r) > huber) {
    w = huber / std::abs(r);
    s.cost += huber * (2.0 * std::abs(r) - huber);
  } else {
    s.cost += r2;
  }
  s.sq += r2;
  const double gx = e.grad_x[i];
  const double gy = e.grad_y[i];
  s.gxx += w * gx * gx;
  s.gxy += w * gx * gy;
  s.gyy += w * gy * gy;
  s.gxr += w * gx * r;
  s.gyr += w * gy * r;
  if (kExposure) {
    const double I = e.intensity[i];
    s.gxI += w * gx * I;
    s.gyI += w * gy * I;
    s.II += w * I * I;
    s.Ir += w * I * r;
  }
}

// The per-pixel sums of accumulate_patch, with the kernel and the exposure column decided at
// compile time. Two pixels at a time in two lanes of doubles (SSE2 / NEON; the compiler does not
// vectorise the sums itself without reassociating them), lanes added at the end: the same sums
// in another order, to the last bits. The Huber weight min(1, huber / |r|) is
// huber / max(|r|, huber) (exactly 1 inside the kernel) and its cost huber (2 |r| - huber) beyond
// it is r^2 - (|r| - huber)^2.
template <bool kExposure, bool kRobust>
PixelSums pixel_sums(const PatchEval& e, double huber) {
  using V = Eigen::Array2d;
  using F = Eigen::Map<const Eigen::Array2f>;
  V gxx = V::Zero(), gxy = V::Zero(), gyy = V::Zero(), gxI = V::Zero(), gyI = V::Zero();
  V II = V::Zero(), gxr = V::Zero(), gyr = V::Zero(), Ir = V::Zero(), cost = V::Zero();
  V sq = V::Zero();
  const V h = V::Constant(huber);
  int k = 0;
  for (; k + 2 <= e.pixels; k += 2) {
    const V r = F(e.residual.data() + k).cast<double>();
    const V r2 = r * r;
    V w = V::Ones();
    if constexpr (kRobust) {
      const V ar = r.abs();
      const V beyond = (ar - h).max(0.0);
      // Inside the kernel the weight is h / h = 1 exactly: the division (the loop's slowest
      // instruction) only for the pairs with a pixel beyond it (few: the kernel is at 1.345
      // sigma of the noise, outliers aside).
      if ((ar > h).any()) w = h / ar.max(h);
      cost += r2 - beyond * beyond;
    } else {
      cost += r2;
    }
    sq += r2;
    const V gx = F(e.grad_x.data() + k).cast<double>();
    const V gy = F(e.grad_y.data() + k).cast<double>();
    const V wgx = w * gx;
    const V wgy = w * gy;
    gxx += wgx * gx;
    gxy += wgx * gy;
    gyy += wgy * gy;
    gxr += wgx * r;
    gyr += wgy * r;
    if constexpr (kExposure) {
      const V I = F(e.intensity.data() + k).cast<double>();
      const V wI = w * I;
      gxI += wgx * I;
      gyI += wgy * I;
      II += wI * I;
      Ir += wI * r;
    }
  }
  PixelSums s;
  s.gxx = gxx.sum();
  s.gxy = gxy.sum();
  s.gyy = gyy.sum();
  s.gxI = gxI.sum();
  s.gyI = gyI.sum();
  s.II = II.sum();
  s.gxr = gxr.sum();
  s.gyr = gyr.sum();
  s.Ir = Ir.sum();
  s.cost = cost.sum();
  s.sq = sq.sum();
  if (k < e.pixels) add_pixel<kExposure, kRobust>(e, k, huber, s);
  return s;
}

}  // namespace

bool evaluate_patch(const cv::Mat& level_image, int level, int patch_size,
                    const Eigen::Vector2d& px, double tau, const float* ref, PatchEval& out) {
  const int P = patch_size;
  const int G = P + 2;  // the patch and a one-pixel border for central differences
  // Not initialised: sample_grid writes every sample used.
  std::array<float, (kMaxPatchSize + 2) * (kMaxPatchSize + 2)> grid;  // NOLINT
  const Eigen::Vector2d u = ImagePyramid::to_level(px, level);
  const double origin = 0.5 * static_cast<double>(P + 1);
  if (!sample_grid(level_image, u.x() - origin, u.y() - origin, G, grid.data())) return false;
  const auto t = static_cast<float>(tau);
  // d / d u (level 0) = d / d u_l / 2^l; central difference over two level pixels.
  const float g = t * 0.5F / static_cast<float>(1 << level);
  out.pixels = P * P;
  static const std::array<float, kMaxPatchPixels> kZeros{};
  const float* r = ref != nullptr ? ref : kZeros.data();
  if (P == 8) {
    fill_patch_fixed<8>(grid.data(), t, g, r, out);
  } else {
    fill_patch(grid.data(), P, t, g, r, out);
  }
  return true;
}

void accumulate_patch(const PatchEval& e, const PoseJacobian& J_pose, double huber, bool exposure,
                      PatchNormals& out) {
  // Sums over the patch in pixel space; the 6 pose columns come from J_pose afterwards.
  const PixelSums s =
      huber > 0.0
          ? (exposure ? pixel_sums<true, true>(e, huber) : pixel_sums<false, true>(e, huber))
          : (exposure ? pixel_sums<true, false>(e, huber) : pixel_sums<false, false>(e, huber));
  Eigen::Matrix2d S;
  S << s.gxx, s.gxy, s.gxy, s.gyy;
  const Eigen::Matrix<double, 6, 2> Jt = J_pose.transpose();
  out.HtWH.topLeftCorner<6, 6>() += Jt * S * J_pose;
  out.HtWr.head<6>() += Jt * Eigen::Vector2d(s.gxr, s.gyr);
  if (exposure) {
    const Eigen::Matrix<double, 6, 1> c = Jt * Eigen::Vector2d(s.gxI, s.gyI);
    out.HtWH.block<6, 1>(0, 6) += c;
    out.HtWH.block<1, 6>(6, 0) += c.transpose();
    out.HtWH(6, 6) += s.II;
    out.HtWr(6) += s.Ir;
  }
  out.cost += s.cost;
  out.sq_error += s.sq;
  out.pixels += e.pixels;
}

Eigen::Matrix<double, Eigen::Dynamic, 7> patch_jacobian(const PatchEval& e,
                                                        const PoseJacobian& J_pose) {
  Eigen::Matrix<double, Eigen::Dynamic, 7> H(e.pixels, 7);
  for (int k = 0; k < e.pixels; ++k) {
    const Eigen::RowVector2d g(e.grad_x[k], e.grad_y[k]);
    H.block<1, 6>(k, 0) = g * J_pose;
    H(k, 6) = e.intensity[k];
  }
  return H;
}

namespace {

// The integer structure-tensor sums of shi_tomasi_score over the p x p window at (x0, y0). kP > 0:
// the edge at compile time (p = kP), so that the compiler unrolls and vectorises the rows, with
// 32-bit sums (at most kP^2 * 2 * 255^2: far below 2^31 for kP <= 16); kP = 0: any edge p, 64-bit
// sums (no overflow for any window the image holds). The same integers either way.
template <int kP>
void structure_sums(const cv::Mat& image, int x0, int y0, int p, std::int64_t& sxx,
                    std::int64_t& sxy, std::int64_t& syy) {
  using Sum = std::conditional_t<kP == 0, std::int64_t, std::int32_t>;
  const int edge = kP > 0 ? kP : p;
  Sum xx = 0, xy = 0, yy = 0;
  for (int y = y0; y < y0 + edge; ++y) {
    const std::uint8_t* row = image.ptr<std::uint8_t>(y) + x0;
    const std::uint8_t* up = image.ptr<std::uint8_t>(y - 1) + x0;
    const std::uint8_t* down = image.ptr<std::uint8_t>(y + 1) + x0;
    for (int x = 0; x < edge; ++x) {
      const std::int32_t dx = static_cast<std::int32_t>(row[x + 1]) - row[x - 1];
      const std::int32_t dy = static_cast<std::int32_t>(down[x]) - up[x];
      xx += dx * dx;
      xy += dx * dy;
      yy += dy * dy;
    }
  }
  sxx = xx;
  sxy = xy;
  syy = yy;
}

}  // namespace

double shi_tomasi_score(const cv::Mat& image, const Eigen::Vector2d& px, int patch_size) {
  const int half = patch_size / 2;
  const int x0 = static_cast<int>(std::lround(px.x())) - half;
  const int y0 = static_cast<int>(std::lround(px.y())) - half;
  if (x0 < 1 || y0 < 1 || x0 + patch_size + 1 > image.cols || y0 + patch_size + 1 > image.rows) {
    return -1.0;
  }
  // Integer sums of the doubled central differences: exact, as the double sums of the halved
  // ones are (quarter-integers far below 2^53), so the score is the same, for less work.
  std::int64_t sxx = 0, sxy = 0, syy = 0;
  if (patch_size == 8) {
    structure_sums<8>(image, x0, y0, patch_size, sxx, sxy, syy);
  } else {
    structure_sums<0>(image, x0, y0, patch_size, sxx, sxy, syy);
  }
  double xx = 0.25 * static_cast<double>(sxx);
  double xy = 0.25 * static_cast<double>(sxy);
  double yy = 0.25 * static_cast<double>(syy);
  const double n = static_cast<double>(patch_size * patch_size);
  xx /= n;
  xy /= n;
  yy /= n;
  // Smallest eigenvalue of [[xx, xy], [xy, yy]].
  return 0.5 * (xx + yy - std::sqrt((xx - yy) * (xx - yy) + 4.0 * xy * xy));
}

}  // namespace livod::estimator::vio

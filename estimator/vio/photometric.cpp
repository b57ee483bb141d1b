#include "estimator/vio/photometric.hpp"

#include <cmath>

#include "estimator/vio/image_pyramid.hpp"

namespace livod::estimator::vio {

namespace {

// The per-pixel loop, with the patch edge known at compile time for the common 8x8 patch (the
// compiler then unrolls and vectorises it).
template <int kP>
void fill_patch(const float* grid, int P, float t, float g, const float* ref, PatchEval& out) {
  const int edge = kP > 0 ? kP : P;
  const int G = edge + 2;
  int k = 0;
  for (int j = 1; j <= edge; ++j) {
    const float* row = grid + j * G;
    const float* up = row - G;
    const float* down = row + G;
    for (int i = 1; i <= edge; ++i, ++k) {
      const float v = row[i];
      out.intensity[k] = v;
      out.residual[k] = t * v - ref[k];
      out.grad_x[k] = g * (row[i + 1] - row[i - 1]);
      out.grad_y[k] = g * (down[i] - up[i]);
    }
  }
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
    fill_patch<8>(grid.data(), P, t, g, r, out);
  } else {
    fill_patch<0>(grid.data(), P, t, g, r, out);
  }
  return true;
}

void accumulate_patch(const PatchEval& e, const PoseJacobian& J_pose, double huber, bool exposure,
                      PatchNormals& out) {
  // Sums over the patch in pixel space; the 6 pose columns come from J_pose afterwards.
  double gxx = 0, gxy = 0, gyy = 0, gxI = 0, gyI = 0, II = 0, gxr = 0, gyr = 0, Ir = 0;
  double cost = 0, sq = 0;
  const bool robust = huber > 0.0;
  for (int k = 0; k < e.pixels; ++k) {
    const double r = e.residual[k];
    const double ar = std::abs(r);
    double w = 1.0;
    if (robust && ar > huber) {
      w = huber / ar;
      cost += huber * (2.0 * ar - huber);
    } else {
      cost += r * r;
    }
    sq += r * r;
    const double gx = e.grad_x[k];
    const double gy = e.grad_y[k];
    const double I = e.intensity[k];
    gxx += w * gx * gx;
    gxy += w * gx * gy;
    gyy += w * gy * gy;
    gxr += w * gx * r;
    gyr += w * gy * r;
    if (exposure) {
      gxI += w * gx * I;
      gyI += w * gy * I;
      II += w * I * I;
      Ir += w * I * r;
    }
  }
  Eigen::Matrix2d S;
  S << gxx, gxy, gxy, gyy;
  const Eigen::Matrix<double, 6, 2> Jt = J_pose.transpose();
  out.HtWH.topLeftCorner<6, 6>() += Jt * S * J_pose;
  out.HtWr.head<6>() += Jt * Eigen::Vector2d(gxr, gyr);
  if (exposure) {
    const Eigen::Matrix<double, 6, 1> c = Jt * Eigen::Vector2d(gxI, gyI);
    out.HtWH.block<6, 1>(0, 6) += c;
    out.HtWH.block<1, 6>(6, 0) += c.transpose();
    out.HtWH(6, 6) += II;
    out.HtWr(6) += Ir;
  }
  out.cost += cost;
  out.sq_error += sq;
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

double shi_tomasi_score(const cv::Mat& image, const Eigen::Vector2d& px, int patch_size) {
  const int half = patch_size / 2;
  const int x0 = static_cast<int>(std::lround(px.x())) - half;
  const int y0 = static_cast<int>(std::lround(px.y())) - half;
  if (x0 < 1 || y0 < 1 || x0 + patch_size + 1 > image.cols || y0 + patch_size + 1 > image.rows) {
    return -1.0;
  }
  double xx = 0, xy = 0, yy = 0;
  for (int y = y0; y < y0 + patch_size; ++y) {
    const std::uint8_t* row = image.ptr<std::uint8_t>(y);
    const std::uint8_t* up = image.ptr<std::uint8_t>(y - 1);
    const std::uint8_t* down = image.ptr<std::uint8_t>(y + 1);
    for (int x = x0; x < x0 + patch_size; ++x) {
      const double dx = 0.5 * (static_cast<double>(row[x + 1]) - static_cast<double>(row[x - 1]));
      const double dy = 0.5 * (static_cast<double>(down[x]) - static_cast<double>(up[x]));
      xx += dx * dx;
      xy += dx * dy;
      yy += dy * dy;
    }
  }
  const double n = static_cast<double>(patch_size * patch_size);
  xx /= n;
  xy /= n;
  yy /= n;
  // Smallest eigenvalue of [[xx, xy], [xy, yy]].
  return 0.5 * (xx + yy - std::sqrt((xx - yy) * (xx - yy) + 4.0 * xy * xy));
}

}  // namespace livod::estimator::vio

#include "tools/sim/camera_sim.hpp"

#include <algorithm>
#include <cmath>

namespace livod::sim {

CameraSim::CameraSim(const CameraSimParams& params) : params_(params), model_(params.intrinsics) {
  const auto& k = params.intrinsics;
  rays_cam_.resize(static_cast<std::size_t>(k.width) * static_cast<std::size_t>(k.height));
  for (int y = 0; y < k.height; ++y) {
    for (int x = 0; x < k.width; ++x) {
      const auto ray = model_.unproject(Eigen::Vector2d(x, y));
      // A pixel the lens model cannot invert (far outside a fisheye circle) sees nothing.
      rays_cam_[static_cast<std::size_t>(y) * static_cast<std::size_t>(k.width) +
                static_cast<std::size_t>(x)] = ray ? *ray : Eigen::Vector3d::Zero();
    }
  }
}

double CameraSim::exposure_at(double t) const {
  double e = params_.exposure_s * (1.0 + params_.exposure_variation *
                                             std::sin(2.0 * M_PI * t / params_.exposure_period_s));
  for (const auto& step : params_.exposure_steps) {
    if (t >= step.t_s) e *= step.factor;
  }
  return e;
}

double CameraSim::ideal_intensity(const World& world, const Eigen::Isometry3d& T_world_cam,
                                  double exposure_s, int x, int y) const {
  const auto& ray_cam =
      rays_cam_[static_cast<std::size_t>(y) * static_cast<std::size_t>(params_.intrinsics.width) +
                static_cast<std::size_t>(x)];
  const double gain = params_.full_scale * exposure_s / params_.reference_exposure_s;
  if (ray_cam.squaredNorm() == 0.0) return 0.0;
  const Eigen::Vector3d dir = T_world_cam.linear() * ray_cam;
  Hit hit;
  if (!world.intersect(T_world_cam.translation(), dir, 1e-3, params_.max_range_m, hit)) {
    return gain * params_.sky_albedo;
  }
  return gain * World::albedo(*hit.surface, hit.point);
}

void CameraSim::render(const World& world, const Eigen::Isometry3d& T_world_cam, double exposure_s,
                       std::mt19937_64& rng, GreyImage& out, const MovingObjects* movers,
                       double time) const {
  const bool moving = movers != nullptr && !movers->empty();
  const int w = params_.intrinsics.width;
  const int h = params_.intrinsics.height;
  out.width = w;
  out.height = h;
  out.pixels.resize(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  std::normal_distribution<double> noise(0.0, params_.noise_sigma);
  // ideal_intensity() per pixel, with the per-frame work hoisted and the texture's lattice cells
  // cached between neighbouring pixels: the same values, faster.
  const double gain = params_.full_scale * exposure_s / params_.reference_exposure_s;
  const Eigen::Matrix3d R_world_cam = T_world_cam.linear();
  const Eigen::Vector3d origin = T_world_cam.translation();
  AlbedoCache cache;
  Hit hit;
  for (std::size_t i = 0; i < out.pixels.size(); ++i) {
    const Eigen::Vector3d& ray_cam = rays_cam_[i];
    double v = 0.0;
    if (ray_cam.squaredNorm() != 0.0) {
      const Eigen::Vector3d dir = R_world_cam * ray_cam;
      bool seen = world.intersect(origin, dir, 1e-3, params_.max_range_m, hit);
      if (moving) {
        Hit moving_hit;
        if (movers->intersect(time, origin, dir, 1e-3, seen ? hit.range : params_.max_range_m,
                              moving_hit)) {
          hit = moving_hit;
          seen = true;
        }
      }
      v = seen ? gain * World::albedo(*hit.surface, hit.point, cache) : gain * params_.sky_albedo;
    }
    if (params_.noise_sigma > 0.0) v += noise(rng);
    out.pixels[i] = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
  }
}

}  // namespace livod::sim

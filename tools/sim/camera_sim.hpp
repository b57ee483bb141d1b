#pragma once
// Global-shutter camera simulation: each pixel's ray (through the real lens model, distortion
// included) is cast into the textured world at the frame's mid-exposure pose. Intensity is the
// surface albedo (view-independent, so photometric constancy holds up to exposure) scaled by the
// exposure time, plus Gaussian sensor noise, quantised to 8 bits.

#include <Eigen/Geometry>
#include <cstdint>
#include <random>
#include <vector>

#include "core/camera_model.hpp"
#include "tools/sim/moving_objects.hpp"
#include "tools/sim/world.hpp"

namespace livod::sim {

// An auto-exposure-like step: from t_s on, the exposure is multiplied by `factor`.
struct ExposureStep {
  double t_s = 0.0;
  double factor = 1.0;
};

// A span of scenario time without frames (a camera that stops and comes back).
struct CameraOutage {
  double begin_s = 0.0;
  double end_s = 0.0;
};

struct CameraSimParams {
  CameraIntrinsics intrinsics;
  double rate_hz = 10.0;
  double exposure_s = 0.004;        // nominal exposure
  double exposure_variation = 0.3;  // relative amplitude of slow exposure changes (auto exposure)
  double exposure_period_s = 7.0;   // period of that variation
  double reference_exposure_s = 0.004;  // exposure at which albedo 1.0 maps to `full_scale`
  double full_scale = 230.0;            // grey level of albedo 1.0 at the reference exposure
  double noise_sigma = 1.5;             // grey levels
  double sky_albedo = 0.9;              // rays that hit nothing (outdoors)
  double max_range_m = 300.0;
  std::vector<ExposureStep> exposure_steps;  // on top of the slow variation
  std::vector<CameraOutage> outages;

  // True when a frame at mid-exposure time t falls into an outage (it is not produced).
  [[nodiscard]] bool in_outage(double t) const {
    for (const auto& o : outages) {
      if (t >= o.begin_s && t < o.end_s) return true;
    }
    return false;
  }
};

// An 8-bit mono image, row-major, width * height bytes (no OpenCV in this header).
struct GreyImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;
  [[nodiscard]] std::uint8_t at(int x, int y) const {
    return pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                  static_cast<std::size_t>(x)];
  }
};

class CameraSim {
 public:
  explicit CameraSim(const CameraSimParams& params);

  // Exposure time of the frame with mid-exposure at scenario time t.
  [[nodiscard]] double exposure_at(double t) const;

  // Renders the world seen from T_world_cam (camera frame: z forward, x right, y down), with the
  // moving objects where they are at scenario time `time` (global shutter) when given.
  void render(const World& world, const Eigen::Isometry3d& T_world_cam, double exposure_s,
              std::mt19937_64& rng, GreyImage& out, const MovingObjects* movers = nullptr,
              double time = 0.0) const;

  // The noise-free intensity (before quantisation) of the surface a pixel sees, for tests.
  [[nodiscard]] double ideal_intensity(const World& world, const Eigen::Isometry3d& T_world_cam,
                                       double exposure_s, int x, int y) const;

  [[nodiscard]] const CameraModel& model() const { return model_; }
  [[nodiscard]] const CameraSimParams& params() const { return params_; }

 private:
  CameraSimParams params_;
  CameraModel model_;
  std::vector<Eigen::Vector3d> rays_cam_;  // unit ray per pixel (row-major)
};

}  // namespace livod::sim

// Reads `camera:` of a camera sensor: projection model, size, intrinsics and distortion, and the
// capture settings livod applies.

#include "daemon/config/readers.hpp"

namespace livod::daemon::config_detail {

void read_camera(MapReader& c, CameraConfig& camera, bool& ok) {
  ProblemList& problems = c.problems();
  constexpr long long kMaxImageSide_px = 20000;
  ok = true;
  if (const auto v = c.take("model"); v && !v->node.IsNull()) {
    if (auto m = parse_enum<CameraModel>(problems, *v)) {
      camera.model = *m;
    } else {
      ok = false;
    }
  }
  const auto width = c.require("width", "pixels");
  const auto height = c.require("height", "pixels");
  std::optional<long long> w;
  std::optional<long long> h;
  if (width) w = parse_integer(problems, *width, 1, kMaxImageSide_px);
  if (height) h = parse_integer(problems, *height, 1, kMaxImageSide_px);
  if (w) camera.width = static_cast<int>(*w);
  if (h) camera.height = static_cast<int>(*h);
  ok = ok && w && h;

  if (const auto v = c.require("intrinsics", "[fx, fy, cx, cy] in pixels")) {
    const auto k = parse_numbers(problems, *v, 4, 4, closed(0.0, 1e5));
    if (k) {
      for (std::size_t i = 0; i < 4; ++i) camera.intrinsics[i] = (*k)[i];
      if (camera.intrinsics[0] <= 0.0 || camera.intrinsics[1] <= 0.0) {
        problems.error(ProblemKind::out_of_range, v->path, v->at, "fx and fy must be > 0");
        ok = false;
      } else if (w && h &&
                 (camera.intrinsics[2] > static_cast<double>(*w) ||
                  camera.intrinsics[3] > static_cast<double>(*h))) {
        problems.error(ProblemKind::out_of_range, v->path, v->at,
                       "the principal point (" + format_number(camera.intrinsics[2]) + ", " +
                           format_number(camera.intrinsics[3]) + ") lies outside the " +
                           std::to_string(*w) + "x" + std::to_string(*h) + " image");
        ok = false;
      }
    } else {
      ok = false;
    }
  } else {
    ok = false;
  }

  if (const auto v = c.take("distortion"); v && !v->node.IsNull()) {
    const auto d = parse_numbers(problems, *v, 0, 5, closed(-100.0, 100.0));
    if (d) {
      const std::size_t n = d->size();
      const bool valid =
          camera.model == CameraModel::pinhole ? (n == 0 || n == 4 || n == 5) : n == 4;
      if (valid) {
        camera.distortion = *d;
      } else {
        problems.error(ProblemKind::invalid_value, v->path, v->at,
                       camera.model == CameraModel::pinhole
                           ? "pinhole (radial-tangential) distortion has 4 [k1, k2, p1, p2] or 5 "
                             "[k1, k2, p1, p2, k3] coefficients, got " +
                                 std::to_string(n)
                           : "equidistant distortion has 4 coefficients [k1, k2, k3, k4], got " +
                                 std::to_string(n));
        ok = false;
      }
    } else {
      ok = false;
    }
  } else if (camera.model == CameraModel::equidistant) {
    problems.error(ProblemKind::missing_key, c.child_path("distortion"), c.at(),
                   "an equidistant camera needs its 4 coefficients [k1, k2, k3, k4]");
    ok = false;
  }

  if (const auto v = c.take("scale"); v && !v->node.IsNull()) {
    const auto scale = parse_double(problems, *v, left_open(0.0, 1.0));
    if (scale) camera.scale = *scale;
    ok = ok && scale.has_value();
  }
  c.read_optional("exposure_s", camera.exposure_s, left_open(0.0, 1.0));
  c.read_optional("frame_rate_hz", camera.frame_rate_hz, left_open(0.0, 1000.0));
  c.read("decimation", camera.decimation, 1, 1000);
  c.finish();
}

}  // namespace livod::daemon::config_detail

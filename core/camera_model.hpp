#pragma once
// Camera projection models shared by the estimator (VIO) and the simulator (rendering):
// pinhole with radial-tangential (radtan) distortion and equidistant fisheye (Kannala-Brandt
// k1..k4). Each provides project() with the exact Jacobian of the model (not the pinhole one:
// FAST-LIVO2 defect 9) and unproject() by Gauss-Newton inversion of the distortion.
//
// Camera frame: z forward (optical axis), x right, y down. Pixel (0, 0) is the centre of the top
// left pixel.

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>

namespace livod {

struct CameraIntrinsics {
  enum class Model { kPinholeRadtan, kEquidistant };
  Model model = Model::kPinholeRadtan;
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  // radtan: k1, k2, p1, p2; equidistant: k1, k2, k3, k4
  std::array<double, 4> distortion{0, 0, 0, 0};
  // radtan only: the sixth-order radial term (OpenCV's and Kalibr's fifth coefficient); 0 = none.
  double radtan_k3 = 0.0;

  // The same camera with the image resized by `scale` (FAST-LIVO2's `scale` option).
  [[nodiscard]] CameraIntrinsics scaled(double scale) const;
};

class CameraModel {
 public:
  explicit CameraModel(const CameraIntrinsics& intrinsics) : k_(intrinsics) {}

  // Pixel of a point in the camera frame; nullopt behind the camera (z <= min_depth) or, for the
  // equidistant model, beyond 180 deg. `J` (optional) receives d pixel / d p_cam.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_cam,
                                         Eigen::Matrix<double, 2, 3>* J = nullptr) const;

  // Unit bearing (z > 0 for the pinhole model) of a pixel. nullopt if the iteration fails.
  [[nodiscard]] std::optional<Eigen::Vector3d> unproject(const Eigen::Vector2d& pixel) const;

  [[nodiscard]] bool in_image(const Eigen::Vector2d& px, double border = 0.0) const {
    return px.x() >= border && px.y() >= border && px.x() <= k_.width - 1 - border &&
           px.y() <= k_.height - 1 - border;
  }

  [[nodiscard]] const CameraIntrinsics& intrinsics() const { return k_; }

 private:
  // Distortion on normalised coordinates (pinhole) with its 2x2 Jacobian.
  Eigen::Vector2d distort_radtan(const Eigen::Vector2d& m, Eigen::Matrix2d* J) const;

  CameraIntrinsics k_;
};

}  // namespace livod

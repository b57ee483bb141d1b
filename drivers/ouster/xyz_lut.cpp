#include "drivers/ouster/xyz_lut.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

namespace livod::drivers::ouster {

XyzLut::XyzLut(const SensorMetadata& metadata) {
  constexpr double kDeg = std::numbers::pi / 180.0;
  const std::size_t rows = metadata.beam_altitude_angles_deg.size();
  beams_.reserve(rows);
  for (std::size_t u = 0; u < rows; ++u) {
    const double theta_a = -metadata.beam_azimuth_angles_deg[u] * kDeg;
    const double phi = metadata.beam_altitude_angles_deg[u] * kDeg;
    beams_.push_back({static_cast<float>(std::cos(theta_a) * std::cos(phi)),
                      static_cast<float>(std::sin(theta_a) * std::cos(phi)),
                      static_cast<float>(std::sin(phi))});
  }

  const double b03 = metadata.T_lidar_beam_mm(0, 3);
  const double b23 = metadata.T_lidar_beam_mm(2, 3);
  beam_offset_mm_ = static_cast<float>(std::hypot(b03, b23));
  beam_origin_x_mm_ = static_cast<float>(b03);

  const Eigen::Matrix3d R_sensor_lidar = metadata.T_sensor_lidar_mm.topLeftCorner<3, 3>();
  const Eigen::Vector3d t_sensor_lidar_mm = metadata.T_sensor_lidar_mm.topRightCorner<3, 1>();
  offset_m_ =
      (1e-3 * (R_sensor_lidar * Eigen::Vector3d(0, 0, b23) + t_sensor_lidar_mm)).cast<float>();

  const std::uint32_t w = metadata.format.columns_per_frame;
  columns_.resize(w);
  for (std::uint32_t v = 0; v < w; ++v) {
    const double theta_e = 2.0 * std::numbers::pi * (1.0 - static_cast<double>(v) / w);
    const Eigen::Matrix3d m =
        1e-3 * R_sensor_lidar *
        Eigen::AngleAxisd(theta_e, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c)
        columns_[v][static_cast<std::size_t>(r * 3 + c)] = static_cast<float>(m(r, c));
    }
  }
}

}  // namespace livod::drivers::ouster

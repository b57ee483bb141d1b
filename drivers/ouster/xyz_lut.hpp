#pragma once
// Range -> point in the Ouster *sensor* frame (x forward, y left, z up; metres), following the
// reference projection (sensor-protocols.md §3.6, ouster-sdk make_xyz_lut):
//
//   theta_e = 2 pi (1 - v / W)        v = measurement_id (the staggered column the pixel was
//   theta_a = -azimuth[u]             measured in; no destaggering is involved)
//   phi     = altitude[u]
//   n       = |(B03, B23)|            B = T_lidar_beam (mm)
//   p_lidar = Rz(theta_e) ((r - n) b_u + (B03, 0, 0)) + (0, 0, B23),
//             b_u = (cos theta_a cos phi, sin theta_a cos phi, sin phi)
//   p_sensor = 1e-3 (R_sensor_lidar p_lidar + t_sensor_lidar)
//
// The table is factored instead of one entry per pixel: per row the unit vector b_u, per column
// the 3x3 matrix M_v = 1e-3 R_sensor_lidar Rz(theta_e), and one constant offset. For 128 x 2048
// that is 75 KB (stays in L2) instead of the 6 MB a per-pixel direction+offset table takes, for
// 9 more multiply-adds per point.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "drivers/ouster/metadata.hpp"

namespace livod::drivers::ouster {

class XyzLut {
 public:
  explicit XyzLut(const SensorMetadata& metadata);

  [[nodiscard]] std::uint32_t rows() const { return static_cast<std::uint32_t>(beams_.size()); }
  [[nodiscard]] std::uint32_t columns() const {
    return static_cast<std::uint32_t>(columns_.size());
  }

  // Point of row `u` measured in column `v` at `range_mm` (> 0), in the sensor frame, metres.
  // u < rows(), v < columns() (the packet decoder has checked both).
  [[nodiscard]] Eigen::Vector3f point(std::uint32_t u, std::uint32_t v,
                                      std::uint32_t range_mm) const {
    const Beam& b = beams_[u];
    const float s = static_cast<float>(range_mm) - beam_offset_mm_;
    const float qx = s * b.x + beam_origin_x_mm_;
    const float qy = s * b.y;
    const float qz = s * b.z;
    const std::array<float, 9>& m = columns_[v];
    return {m[0] * qx + m[1] * qy + m[2] * qz + offset_m_.x(),
            m[3] * qx + m[4] * qy + m[5] * qz + offset_m_.y(),
            m[6] * qx + m[7] * qy + m[8] * qz + offset_m_.z()};
  }

 private:
  struct Beam {
    float x, y, z;
  };
  std::vector<Beam> beams_;                    // b_u per row
  std::vector<std::array<float, 9>> columns_;  // M_v per column, row-major, includes mm -> m
  Eigen::Vector3f offset_m_;                   // 1e-3 (R_sensor_lidar (0, 0, B23) + t_sensor_lidar)
  float beam_offset_mm_ = 0.0F;                // n
  float beam_origin_x_mm_ = 0.0F;              // B03
};

}  // namespace livod::drivers::ouster

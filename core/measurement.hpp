#pragma once
// Measurement types passed from drivers to the estimator. SI units everywhere (m, s, rad, m/s^2);
// unit conversions happen once, in the driver that decodes the wire format.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/time.hpp"

namespace livod {

// One IMU sample, already converted to SI and expressed in the IMU's own frame.
struct ImuSample {
  Stamp stamp;
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();
};

// A LiDAR scan as structure-of-arrays, in the LiDAR frame (x forward, y left, z up).
// `start` stamps the scan's first point; each point's own time is start + t_offset_ns[i].
// Capacity is reserved once and reused: clear() keeps the allocations, so a driver that reuses
// one scan object does not allocate in steady state.
struct LidarScan {
  Stamp start;
  std::uint32_t sequence = 0;  // scans counted from 0 by the assembler that produced it

  std::vector<float> x, y, z;              // metres, LiDAR frame
  std::vector<float> intensity;            // reflectivity / intensity as the sensor reports it
  std::vector<std::uint16_t> ring;         // laser / line / beam index
  std::vector<std::uint8_t> return_index;  // 0 = first/strongest, 1 = second, ...
  std::vector<std::int32_t> t_offset_ns;   // ns from `start` (a scan spans < 2.1 s)
  std::vector<std::uint8_t> valid;         // 0 = no return / filtered out, kept for layout

  [[nodiscard]] std::size_t size() const { return x.size(); }
  [[nodiscard]] bool empty() const { return x.empty(); }

  void reserve(std::size_t n) {
    x.reserve(n);
    y.reserve(n);
    z.reserve(n);
    intensity.reserve(n);
    ring.reserve(n);
    return_index.reserve(n);
    t_offset_ns.reserve(n);
    valid.reserve(n);
  }

  void clear() {
    x.clear();
    y.clear();
    z.clear();
    intensity.clear();
    ring.clear();
    return_index.clear();
    t_offset_ns.clear();
    valid.clear();
  }

  void push_back(float px, float py, float pz, float pintensity, std::uint16_t pring,
                 std::uint8_t preturn, std::int32_t poffset_ns, bool pvalid = true) {
    x.push_back(px);
    y.push_back(py);
    z.push_back(pz);
    intensity.push_back(pintensity);
    ring.push_back(pring);
    return_index.push_back(preturn);
    t_offset_ns.push_back(poffset_ns);
    valid.push_back(pvalid ? 1 : 0);
  }

  // Time of the latest point after `start` (points need not be in time order).
  [[nodiscard]] std::int32_t span_ns() const {
    std::int32_t last = 0;
    for (const auto t : t_offset_ns) last = t > last ? t : last;
    return last;
  }

  [[nodiscard]] Eigen::Vector3f point(std::size_t i) const { return {x[i], y[i], z[i]}; }
  [[nodiscard]] MappedTime point_time(std::size_t i) const {
    return start.mapped + Nanoseconds(t_offset_ns[i]);
  }
};

}  // namespace livod

#pragma once
// Reading points out of a sensor_msgs/PointCloud2 without PCL: x, y, z, an intensity field and a
// per-point time field, each of any PointField datatype (int8 ... float64), little- or big-endian.
// Drivers name their per-point time differently and in different units (Ouster "t" uint32 ns
// from scan start, Velodyne "time" float32 s from scan start, Hesai/Robosense "timestamp"
// float64 absolute s, livox_ros_driver2 "timestamp" float64 ns...), so the helper returns the raw
// value as a double and the caller converts the unit once.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "io/rosbag/ros_messages.hpp"

namespace livod::io::rosbag {

struct CloudPoint {
  float x = 0;
  float y = 0;
  float z = 0;
  float intensity = 0;  // 0 when no intensity field was asked for
  double time = 0;      // raw value of the time field; 0 when none was asked for
  // Laser / line of the point: the ring field when one was asked for (out-of-range or non-finite
  // values read 0), else the row of an organised cloud (Ouster's ROS driver: one row per beam).
  std::uint16_t ring = 0;
};

struct CloudFields {
  std::string x = "x";
  std::string y = "y";
  std::string z = "z";
  std::string intensity = "intensity";  // "" = none ("reflectivity" for some drivers)
  std::string time;                     // "" = none; e.g. "t", "time", "timestamp"
  std::string ring;  // "" = the row index; e.g. "ring" (Velodyne, Ouster), "line" (Livox)
};

// Names of the cloud's fields (for error messages and driver auto-detection).
std::vector<std::string> field_names(const sensor_msgs::PointCloud2& cloud);

// Replaces `out` with the cloud's height * width points (NaN points included, in row-major order;
// filtering is the caller's policy). Throws livod::FormatError when a requested field is missing,
// has an unknown datatype or lies outside point_step, or when data is shorter than the declared
// height * row_step / width * point_step.
void extract_points(const sensor_msgs::PointCloud2& cloud, const CloudFields& fields,
                    std::vector<CloudPoint>& out);

// One element of `field` in the point starting at `point` (which holds at least point_step
// bytes), converted to double.
double read_point_field(std::span<const std::uint8_t> point, const sensor_msgs::PointField& field,
                        bool big_endian);

}  // namespace livod::io::rosbag

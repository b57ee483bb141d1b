// ROS velodyne_pointcloud / nebula calibration YAML: `lasers:` is a list of maps with laser_id,
// vert_correction and rot_correction (radians), dist_correction, dist_correction_x/_y,
// vert_offset_correction, horiz_offset_correction, focal_distance (metres) and focal_slope;
// optional `num_lasers` and `distance_resolution` (metres).

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <string>

#include "core/error.hpp"
#include "drivers/velodyne/calibration.hpp"

namespace livod::drivers::velodyne {
namespace {

double optional_number(const YAML::Node& laser, const char* key) {
  const YAML::Node value = laser[key];
  if (!value) return 0.0;  // ROS velodyne treats missing corrections as zero
  return value.as<double>();
}

}  // namespace

Calibration parse_ros_yaml(std::string_view text, const std::string& source) {
  try {
    const YAML::Node root = YAML::Load(std::string(text));
    if (!root.IsMap() || !root["lasers"] || !root["lasers"].IsSequence()) {
      throw Error(source + ": no 'lasers' list (not a ROS/nebula Velodyne calibration?)");
    }
    const YAML::Node list = root["lasers"];
    std::size_t lasers = list.size();
    if (root["num_lasers"]) {
      const int n = root["num_lasers"].as<int>();
      if (n < 0 || static_cast<std::size_t>(n) != list.size()) {
        throw Error(source + ": num_lasers is " + std::to_string(n) + " but 'lasers' lists " +
                    std::to_string(list.size()));
      }
      lasers = static_cast<std::size_t>(n);
    }

    Calibration calibration;
    calibration.source = source;
    calibration.lasers.resize(lasers);
    std::vector<bool> seen(lasers, false);
    for (const auto& laser : list) {
      if (!laser.IsMap() || !laser["laser_id"]) {
        throw Error(source + ": a 'lasers' entry has no laser_id");
      }
      const int id = laser["laser_id"].as<int>();
      if (id < 0 || static_cast<std::size_t>(id) >= lasers || seen[static_cast<std::size_t>(id)]) {
        throw Error(source + ": laser_id " + std::to_string(id) + " is out of range or repeated");
      }
      auto& l = calibration.lasers[static_cast<std::size_t>(id)];
      l.vert_correction_rad = optional_number(laser, "vert_correction");
      l.rot_correction_rad = optional_number(laser, "rot_correction");
      l.dist_correction_m = optional_number(laser, "dist_correction");
      l.dist_correction_x_m = optional_number(laser, "dist_correction_x");
      l.dist_correction_y_m = optional_number(laser, "dist_correction_y");
      l.vert_offset_m = optional_number(laser, "vert_offset_correction");
      l.horiz_offset_m = optional_number(laser, "horiz_offset_correction");
      l.focal_distance_m = optional_number(laser, "focal_distance");
      l.focal_slope = optional_number(laser, "focal_slope");
      seen[static_cast<std::size_t>(id)] = true;
    }
    if (root["distance_resolution"]) {
      calibration.distance_resolution_m = root["distance_resolution"].as<double>();
    }
    return calibration;
  } catch (const YAML::Exception& e) {
    const auto offset = e.mark.pos < 0 ? 0 : static_cast<std::uint64_t>(e.mark.pos);
    throw FormatError(source, offset, "invalid calibration YAML: " + e.msg);
  }
}

}  // namespace livod::drivers::velodyne

#pragma once
// Per-laser geometric corrections. Sources: a VeloView XML file (degrees, centimetres), a
// ROS velodyne / nebula YAML file (radians, metres), or the built-in nominal table of a model.
// Everything is stored in SI units (radians, metres).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/velodyne/model.hpp"

namespace livod::drivers::velodyne {

struct LaserCorrection {
  double vert_correction_rad = 0.0;  // elevation of the beam
  double rot_correction_rad = 0.0;   // azimuth offset: the beam points at (azimuth - rot)
  double dist_correction_m = 0.0;    // added to every non-zero range
  double vert_offset_m = 0.0;        // beam origin offset perpendicular to the beam, vertical
  double horiz_offset_m = 0.0;       // beam origin offset, horizontal
  // HDL-64E two-point distance and focal/intensity corrections: read so that such files load,
  // not applied (none of the supported models uses them; see docs/drivers/velodyne.md).
  double dist_correction_x_m = 0.0;
  double dist_correction_y_m = 0.0;
  double focal_distance_m = 0.0;
  double focal_slope = 0.0;
};

struct Calibration {
  std::vector<LaserCorrection> lasers;  // indexed by laser id
  // Distance LSB stated by the file, if any. Informational: the decoder uses the model's wire
  // unit (§4.1; e.g. VROS's VLS128.yaml says 7 mm while the sensor sends 4 mm).
  std::optional<double> distance_resolution_m;
  std::string source;  // file path or "built-in <model>"

  // Ring number of each laser: its rank by elevation, 0 = lowest beam (ties: lower laser id
  // first). This is the ROS/nebula "ring"/"channel" convention.
  [[nodiscard]] std::vector<std::uint16_t> rings() const;
};

// The nominal factory table of a model (vertical and rotational corrections only).
[[nodiscard]] Calibration default_calibration(Model model);

// Reads a calibration file, VeloView XML or ROS/nebula YAML (detected from the content). Throws
// livod::FormatError (with the byte offset) for malformed files and livod::Error for files
// that parse but are not a usable calibration.
[[nodiscard]] Calibration load_calibration(const std::filesystem::path& path);

[[nodiscard]] Calibration parse_veloview_xml(std::string_view text, const std::string& source);
[[nodiscard]] Calibration parse_ros_yaml(std::string_view text, const std::string& source);

// Throws livod::Error if the calibration does not describe `model` (laser count, finite values).
void check_calibration_matches(const Calibration& calibration, Model model);

}  // namespace livod::drivers::velodyne

#include "drivers/velodyne/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numeric>
#include <sstream>

#include "core/error.hpp"

namespace livod::drivers::velodyne {

std::vector<std::uint16_t> Calibration::rings() const {
  std::vector<std::size_t> order(lasers.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [this](std::size_t a, std::size_t b) {
    return lasers[a].vert_correction_rad < lasers[b].vert_correction_rad;
  });
  std::vector<std::uint16_t> ring(lasers.size());
  for (std::size_t rank = 0; rank < order.size(); ++rank) {
    ring[order[rank]] = static_cast<std::uint16_t>(rank);
  }
  return ring;
}

Calibration load_calibration(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot open calibration file " + path.string());
  std::ostringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  // VeloView files are XML (they start with '<' after optional whitespace); everything else is
  // read as YAML.
  const auto first = text.find_first_not_of(" \t\r\n\xEF\xBB\xBF");
  if (first != std::string::npos && text[first] == '<') {
    return parse_veloview_xml(text, path.string());
  }
  return parse_ros_yaml(text, path.string());
}

void check_calibration_matches(const Calibration& calibration, Model model) {
  const auto& t = traits(model);
  if (static_cast<int>(calibration.lasers.size()) != t.lasers) {
    throw Error(calibration.source + ": calibration has " +
                std::to_string(calibration.lasers.size()) + " lasers, the " + std::string(t.name) +
                " has " + std::to_string(t.lasers));
  }
  constexpr double kMaxElevationRad = 1.5;  // |elevation| < ~86 degrees for any real beam
  for (std::size_t i = 0; i < calibration.lasers.size(); ++i) {
    const auto& l = calibration.lasers[i];
    const double values[] = {l.vert_correction_rad, l.rot_correction_rad, l.dist_correction_m,
                             l.vert_offset_m, l.horiz_offset_m};
    const bool finite = std::all_of(std::begin(values), std::end(values),
                                    [](double v) { return std::isfinite(v); });
    if (!finite || std::abs(l.vert_correction_rad) > kMaxElevationRad) {
      throw Error(calibration.source + ": laser " + std::to_string(i) +
                  " has a non-finite or impossible correction");
    }
  }
}

}  // namespace livod::drivers::velodyne

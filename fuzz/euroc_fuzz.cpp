// libFuzzer target: the EuRoC/ASL csv, TUM and sensor.yaml parsers on arbitrary text. The first
// byte picks the parser. Only livod::FormatError may escape (yaml-cpp exceptions must have been
// translated); anything else aborts.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "core/error.hpp"
#include "io/euroc.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);
  const std::string source = "fuzz";
  try {
    switch (data[0] % 6) {
      case 0: {
        const auto images = livod::io::parse_euroc_camera_csv(text, source, "/data");
        for (std::size_t i = 1; i < images.size(); ++i) {
          if (images[i].timestamp <= images[i - 1].timestamp) std::abort();
        }
        break;
      }
      case 1: {
        const auto imu = livod::io::parse_euroc_imu_csv(text, source);
        for (const auto& s : imu) {
          if (!s.gyro_rad_s.allFinite() || !s.accel_m_s2.allFinite()) std::abort();
        }
        break;
      }
      case 2:
        livod::io::parse_euroc_groundtruth_csv(text, source);
        break;
      case 3:
        livod::io::parse_tum_trajectory(text, source);
        break;
      case 4: {
        const auto camera = livod::io::parse_euroc_camera_yaml(text, source);
        if (camera.width <= 0 || camera.height <= 0 || !camera.T_body_sensor.allFinite()) {
          std::abort();
        }
        break;
      }
      default:
        livod::io::parse_euroc_imu_yaml(text, source);
        break;
    }
  } catch (const livod::FormatError&) {
    // Malformed input is reported, which is the expected outcome for most inputs.
  }
  return 0;
}

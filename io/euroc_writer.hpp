#pragma once
// Writes camera frames as an EuRoC / ASL camera folder, losslessly, so that a recording replays
// through the same reader (io/euroc.hpp) as the public datasets:
//   <folder>/data/<timestamp ns>.png   8- or 16-bit mono, or 8-bit BGR (PNG is lossless)
//   <folder>/data.csv                  #timestamp [ns],filename,exposure_ns
//   <folder>/sensor.yaml               (write_euroc_camera_yaml)
// The timestamp is the frame's time on the common timeline (livod uses mid-exposure); the third
// column is livod's extension (exposure duration, ns; 0 when unknown), read back by
// parse_euroc_camera_csv.
// `livod record` writes its camera folders with it on the recorder thread (docs/record.md): the
// writer allocates (PNG encoding) and belongs on an IO thread, never a capture thread. A frame
// whose PNG cannot be written throws and leaves no file; data.csv names only written frames.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>

#include "core/time.hpp"
#include "io/euroc.hpp"

namespace livod::io {

class EurocCameraWriter {
 public:
  // Creates <folder>/data and <folder>/data.csv (with its header). Throws livod::Error.
  explicit EurocCameraWriter(const std::filesystem::path& folder);

  // Writes one image (CV_8UC1, CV_16UC1 or CV_8UC3). Timestamps must strictly increase (the
  // reader requires it; std::invalid_argument otherwise). Throws livod::Error on write failure.
  void write(SensorTime timestamp, const cv::Mat& image, std::optional<Nanoseconds> exposure);
  // Flushes data.csv; throws livod::Error if it could not be written.
  void flush();

  [[nodiscard]] std::uint64_t frames() const { return frames_; }
  // The PNG files' bytes written so far.
  [[nodiscard]] std::uint64_t bytes() const { return bytes_; }

 private:
  std::filesystem::path folder_;
  std::ofstream csv_;
  std::optional<SensorTime> last_;
  std::uint64_t frames_ = 0;
  std::uint64_t bytes_ = 0;
};

// sensor.yaml in the EuRoC layout (T_BS, rate, resolution, pinhole intrinsics, distortion).
void write_euroc_camera_yaml(const std::filesystem::path& path,
                             const EurocCameraCalibration& calibration);

}  // namespace livod::io

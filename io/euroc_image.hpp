#pragma once
// Decoding of dataset images (EuRoC/ASL folders and others) with OpenCV imgcodecs. Kept apart
// from io/euroc.hpp so that only code that really handles pixels pulls in OpenCV headers; a target
// that includes this header links opencv_core itself (livod_io links OpenCV privately).

#include <filesystem>
#include <opencv2/core/mat.hpp>

#include "io/euroc.hpp"

namespace livod::io {

enum class ImageDecodeMode {
  kAsStored,  // the file's own depth and channels (EuRoC: 8-bit mono)
  kMono8,     // converted to 8-bit single channel
};

// Decodes one image file. Throws livod::Error with the path if it is missing or not decodable.
cv::Mat load_dataset_image(const std::filesystem::path& path,
                           ImageDecodeMode mode = ImageDecodeMode::kAsStored);

inline cv::Mat load_euroc_image(const EurocImageRecord& record,
                                ImageDecodeMode mode = ImageDecodeMode::kAsStored) {
  return load_dataset_image(record.path, mode);
}

}  // namespace livod::io

#include "io/euroc_image.hpp"

#include <opencv2/imgcodecs.hpp>
#include <system_error>

#include "core/error.hpp"

namespace livod::io {

cv::Mat load_dataset_image(const std::filesystem::path& path, ImageDecodeMode mode) {
  // imread only says "empty" on failure; tell a missing file apart from an undecodable one.
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw Error(path.string() + ": image file not found");
  }
  const int flags = mode == ImageDecodeMode::kMono8 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_UNCHANGED;
  cv::Mat image = cv::imread(path.string(), flags);
  if (image.empty()) throw Error(path.string() + ": cannot decode image");
  return image;
}

}  // namespace livod::io

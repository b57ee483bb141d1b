#include "daemon/replay/debug_images.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.hpp"

namespace livod::daemon::replay {

void write_debug_image(const std::filesystem::path& dir, MappedTime t, const cv::Mat& grey,
                       const std::vector<estimator::vio::VioPatchDebug>& patches, int patch_size) {
  using Status = estimator::vio::VioPatchDebug::Status;
  cv::Mat img;
  if (grey.channels() == 1) {
    cv::cvtColor(grey, img, cv::COLOR_GRAY2BGR);
  } else {
    img = grey.clone();
  }
  const int half = patch_size / 2;
  for (const auto& p : patches) {
    cv::Scalar colour;  // BGR
    switch (p.status) {
      case Status::tracked:
        colour = p.rms_after < p.rms_before ? cv::Scalar(0, 200, 0) : cv::Scalar(255, 80, 0);
        break;
      case Status::rejected:
        colour = cv::Scalar(0, 0, 255);
        break;
      case Status::created:
        colour = cv::Scalar(0, 220, 255);
        break;
    }
    const cv::Point c(static_cast<int>(std::lround(p.pixel.x())),
                      static_cast<int>(std::lround(p.pixel.y())));
    cv::rectangle(img, c - cv::Point(half, half), c + cv::Point(half, half), colour, 1);
  }
  const auto path = dir / (std::to_string(t.ns) + ".png");
  if (!cv::imwrite(path.string(), img)) throw Error("cannot write " + path.string());
}

}  // namespace livod::daemon::replay

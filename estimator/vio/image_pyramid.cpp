#include "estimator/vio/image_pyramid.hpp"

#include <opencv2/imgproc.hpp>

namespace livod::estimator::vio {

void ImagePyramid::build(const cv::Mat& grey, int levels) {
  levels_.resize(static_cast<std::size_t>(std::max(1, levels)));
  levels_[0] = grey;
  for (std::size_t l = 1; l < levels_.size(); ++l) {
    // Reuses the level's buffer when the size is unchanged (the steady state).
    cv::pyrDown(levels_[l - 1], levels_[l]);
  }
}

}  // namespace livod::estimator::vio

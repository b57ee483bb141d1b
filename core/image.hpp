#pragma once
// Camera frame. Kept apart from measurement.hpp so that only code that handles images pulls in
// OpenCV headers (compile time on 2 cores matters).

#include <cstdint>
#include <opencv2/core/mat.hpp>

#include "core/time.hpp"

namespace livod {

struct ImageFrame {
  Stamp stamp;                 // as delivered by the camera path (trigger or frame time)
  cv::Mat image;               // 8-bit mono or BGR
  Nanoseconds exposure{0};     // exposure duration; 0 when unknown
  MappedTime trigger_time;     // start of exposure on the common timeline (when known)
  MappedTime mid_exposure;     // the time the estimator uses: trigger + exposure / 2
  std::uint32_t sequence = 0;  // frame counter from the source (gaps = dropped frames)
};

}  // namespace livod

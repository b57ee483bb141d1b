#pragma once
// `livod replay --debug-images DIR`: every image the visual update processed, as it saw it (grey,
// resized by the camera's scale), with its patches drawn - green: tracked and its photometric
// error went down, blue: tracked without improvement, red: rejected (photometric gate), yellow:
// a new visual point. FAST-LIVO2's /rgb_img does the same (green / blue). One PNG per image,
// named by the image's mid-exposure time in ns.

#include <filesystem>
#include <vector>

#include "core/time.hpp"
#include "estimator/vio/vio_processor.hpp"

namespace livod::daemon::replay {

// Throws livod::Error if the file cannot be written.
void write_debug_image(const std::filesystem::path& dir, MappedTime t, const cv::Mat& grey,
                       const std::vector<estimator::vio::VioPatchDebug>& patches, int patch_size);

}  // namespace livod::daemon::replay

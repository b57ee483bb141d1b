#pragma once
// Recorded camera frames for replay, as ReplaySources (sources.hpp) that deliver ImageFrames to
// DecoderSinks::on_image:
//
//  - a folder (format `euroc`): an EuRoC/ASL camera folder (data.csv + data/, with the livod
//    exposure column when present), or a plain image folder with a timestamps file:
//      timestamps.txt   one frame per line, "<time> <file>": time in seconds with a decimal
//                       point (TUM rgb.txt style) or integer nanoseconds; '#' starts a comment
//      times.txt        one time in seconds per line (KITTI), matched to the folder's images
//                       sorted by name (their counts must agree)
//  - one topic of a ROS1 bag (format `rosbag1`): sensor_msgs/Image (mono8, mono16, bgr8, rgb8,
//    bgra8, rgba8 and the 8-bit Bayer encodings) or sensor_msgs/CompressedImage (JPEG, PNG, ...).
//
// Every recording stamps the middle of the exposure (core/image.hpp). Receive times: the bag's
// record time; a folder has none, so its frame time serves as both. Pixels come out 8-bit mono or
// BGR. A frame that cannot be read or decoded is counted and skipped (its summary says how many);
// a folder or topic whose first frames all fail stops the replay with the first error.

#include <filesystem>
#include <memory>
#include <string>

#include "daemon/config/config.hpp"
#include "daemon/replay/sources.hpp"

namespace livod::daemon::replay {

std::unique_ptr<ReplaySource> make_image_folder_source(const std::filesystem::path& folder,
                                                       const SensorConfig& sensor);

std::unique_ptr<ReplaySource> make_bag_image_source(const std::filesystem::path& file,
                                                    const std::string& topic,
                                                    const SensorConfig& sensor);

}  // namespace livod::daemon::replay

#pragma once
// The pure parts of image replay (image_sources.hpp), apart so that the fuzz build can test them:
// timestamps files of plain image folders, and ROS image messages to 8-bit mono or BGR pixels.
// Bad input throws livod::Error (or livod::FormatError), never anything else.

#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "io/rosbag/ros_messages.hpp"

namespace livod::daemon::replay {

// timestamps.txt: "<time> <file>" per line ('#' starts a comment); time in seconds with a decimal
// point or exponent, or integer nanoseconds. Returns (ns, file) in file order.
std::vector<std::pair<std::int64_t, std::string>> parse_timestamps_txt(std::string_view text,
                                                                       const std::string& source);

// times.txt (KITTI): one time in seconds per line ('#' comments and blank lines skipped).
std::vector<std::int64_t> parse_times_txt(std::string_view text, const std::string& source);

// A decimal number of seconds ("1403715273.262142", "12", "1.0364e-01") in ns, exact for plain
// decimals (a double would round the nanoseconds of an epoch time).
std::int64_t parse_seconds_ns(const std::string& text, const std::string& where);

// Any 8- or 16-bit, 1/3/4-channel image as 8-bit mono or BGR (16 bits keep their high byte).
cv::Mat to_mono_or_bgr(const cv::Mat& in);

// sensor_msgs/Image (mono8, mono16, bgr8, rgb8, bgra8, rgba8, 8-bit Bayer) to 8-bit mono or BGR;
// the pixels are copied.
cv::Mat decode_image_message(const io::rosbag::sensor_msgs::Image& msg);

// sensor_msgs/CompressedImage (whatever OpenCV decodes) to 8-bit mono or BGR.
cv::Mat decode_compressed_image(const io::rosbag::sensor_msgs::CompressedImage& msg);

}  // namespace livod::daemon::replay

// libFuzzer target: image replay's parsers and decoders on arbitrary bytes - timestamps.txt and
// times.txt of plain image folders, and sensor_msgs/Image / CompressedImage messages (deserialized
// from the bytes) to 8-bit pixels. The first byte picks the input. Only livod::Error (and its
// FormatError) may escape; a decoded image must be 8-bit mono or BGR of the message's size.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <string>
#include <string_view>

#include "core/error.hpp"
#include "daemon/replay/image_decoding.hpp"

namespace rb = livod::io::rosbag;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data) + 1, size - 1);
  try {
    switch (data[0] % 4) {
      case 0:
        livod::daemon::replay::parse_timestamps_txt(text, "fuzz");
        break;
      case 1:
        livod::daemon::replay::parse_times_txt(text, "fuzz");
        break;
      case 2: {
        rb::sensor_msgs::Image msg;
        rb::deserialize(bytes, msg);
        const cv::Mat img = livod::daemon::replay::decode_image_message(msg);
        if (img.depth() != CV_8U || (img.channels() != 1 && img.channels() != 3) ||
            img.cols != static_cast<int>(msg.width) || img.rows != static_cast<int>(msg.height)) {
          std::abort();
        }
        break;
      }
      default: {
        rb::sensor_msgs::CompressedImage msg;
        rb::deserialize(bytes, msg);
        const cv::Mat img = livod::daemon::replay::decode_compressed_image(msg);
        if (img.depth() != CV_8U || (img.channels() != 1 && img.channels() != 3)) std::abort();
        break;
      }
    }
  } catch (const livod::Error&) {
  }
  return 0;
}

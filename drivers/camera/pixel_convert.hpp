#pragma once
// Wire pixel formats of V4L2 devices and their conversion into the ring's pixel formats, written
// straight into the ring slot (one pass: the only copy of the frame). Pure functions over bytes,
// tested on recorded buffers.
//
//   wire (V4L2 fourcc)  -> mono8              mono16        bgr8
//   GREY                   copy               -             expand
//   Y16  (16-bit LE)       / 256 (rounded)    copy          -
//   YUYV (4:2:2)           the Y samples      -             YUV -> BGR (BT.601, OpenCV)
//   MJPG                   JPEG decode, grey  -             JPEG decode, colour
//   BGR3 / RGB3            to grey            -             copy / swap
//
// MJPEG frames decode with OpenCV (libjpeg) directly into the slot; libjpeg allocates its own
// working memory per frame (the one allocation on the camera capture path; see camera.md).

#include <cstddef>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "drivers/camera/camera_frame.hpp"

namespace livod::camera {

enum class WireFormat : std::uint8_t { kGrey, kY16, kYuyv, kMjpeg, kBgr24, kRgb24 };

// V4L2 fourcc code of a wire format and back.
std::uint32_t fourcc(WireFormat f);
std::optional<WireFormat> wire_format_from_fourcc(std::uint32_t code);
// "GREY", "YUYV", ... (any code, printable or not).
std::string fourcc_name(std::uint32_t code);
// Parses a 4-character code ("GREY", "MJPG"; "Y16" is padded with a space). nullopt if not 1-4
// printable characters.
std::optional<std::uint32_t> parse_fourcc(const std::string& text);

bool can_convert(WireFormat from, PixelFormat to);
// The wire formats worth asking a device for, best first, for a ring format: lossless and cheap
// ones first, MJPEG (lossy, decoding costs CPU) last.
std::vector<WireFormat> preferred_wire_formats(PixelFormat to);

struct WireImage {
  std::span<const std::byte> bytes;  // bytesused of the buffer
  int width = 0;
  int height = 0;
  std::size_t stride = 0;  // bytes per line (bytesperline); unused for MJPEG
  WireFormat format = WireFormat::kGrey;
};

enum class ConvertStatus : std::uint8_t {
  kOk,
  kShortBuffer,   // fewer bytes than the image needs (a truncated or corrupt buffer)
  kDecodeFailed,  // MJPEG did not decode
  kSizeMismatch,  // MJPEG decoded to another size than negotiated
  kUnsupported,   // no conversion between these formats
};
const char* to_string(ConvertStatus s);

// Converts `in` into `out`, a header of the ring format's type and the image size over the ring
// slot. Never reallocates `out`: a frame that does not fit is reported, not converted.
ConvertStatus convert_image(const WireImage& in, cv::Mat& out);

}  // namespace livod::camera

#include "drivers/camera/pixel_convert.hpp"

#include <cstring>
#include <exception>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>

namespace livod::camera {
namespace {

constexpr std::uint32_t code(char a, char b, char c, char d) {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(a)) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(b)) << 8) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(c)) << 16) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(d)) << 24);
}

int bytes_per_wire_pixel(WireFormat f) {
  switch (f) {
    case WireFormat::kGrey:
      return 1;
    case WireFormat::kY16:
    case WireFormat::kYuyv:
      return 2;
    case WireFormat::kBgr24:
    case WireFormat::kRgb24:
      return 3;
    case WireFormat::kMjpeg:
      return 0;
  }
  return 0;
}

// Width and height from a JPEG's frame header (SOFn), without decoding: a corrupt frame that
// claims another size must not make the decoder allocate for it. nullopt when there is none.
std::optional<std::pair<int, int>> jpeg_dimensions(std::span<const std::byte> b) {
  const auto at = [&](std::size_t i) { return static_cast<unsigned>(b[i]); };
  if (b.size() < 4 || at(0) != 0xFF || at(1) != 0xD8) return std::nullopt;  // SOI
  std::size_t i = 2;
  while (i + 4 <= b.size()) {
    if (at(i) != 0xFF) return std::nullopt;
    const unsigned marker = at(i + 1);
    if (marker == 0xFF) {  // fill byte
      ++i;
      continue;
    }
    const std::size_t length = (at(i + 2) << 8) | at(i + 3);
    const bool sof =
        marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (sof) {
      if (i + 9 > b.size() || length < 7) return std::nullopt;
      const int height = static_cast<int>((at(i + 5) << 8) | at(i + 6));
      const int width = static_cast<int>((at(i + 7) << 8) | at(i + 8));
      return std::make_pair(width, height);
    }
    if (length < 2) return std::nullopt;
    i += 2 + length;
  }
  return std::nullopt;
}

}  // namespace

std::uint32_t fourcc(WireFormat f) {
  switch (f) {
    case WireFormat::kGrey:
      return code('G', 'R', 'E', 'Y');
    case WireFormat::kY16:
      return code('Y', '1', '6', ' ');
    case WireFormat::kYuyv:
      return code('Y', 'U', 'Y', 'V');
    case WireFormat::kMjpeg:
      return code('M', 'J', 'P', 'G');
    case WireFormat::kBgr24:
      return code('B', 'G', 'R', '3');
    case WireFormat::kRgb24:
      return code('R', 'G', 'B', '3');
  }
  return 0;
}

std::optional<WireFormat> wire_format_from_fourcc(std::uint32_t c) {
  for (const auto f : {WireFormat::kGrey, WireFormat::kY16, WireFormat::kYuyv, WireFormat::kMjpeg,
                       WireFormat::kBgr24, WireFormat::kRgb24}) {
    if (fourcc(f) == c) return f;
  }
  return std::nullopt;
}

std::string fourcc_name(std::uint32_t c) {
  std::string s;
  for (int i = 0; i < 4; ++i) {
    const char ch = static_cast<char>((c >> (8 * i)) & 0xFF);
    s += (ch >= 0x20 && ch < 0x7F) ? ch : '?';
  }
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

std::optional<std::uint32_t> parse_fourcc(const std::string& text) {
  if (text.empty() || text.size() > 4) return std::nullopt;
  std::string padded = text;
  padded.resize(4, ' ');
  for (const char ch : padded) {
    if (ch < 0x20 || ch >= 0x7F) return std::nullopt;
  }
  return code(padded[0], padded[1], padded[2], padded[3]);
}

bool can_convert(WireFormat from, PixelFormat to) {
  switch (to) {
    case PixelFormat::kMono16:
      return from == WireFormat::kY16;
    case PixelFormat::kMono8:
      return true;
    case PixelFormat::kBgr8:
      return from != WireFormat::kY16;
  }
  return false;
}

std::vector<WireFormat> preferred_wire_formats(PixelFormat to) {
  switch (to) {
    case PixelFormat::kMono8:
      return {WireFormat::kGrey,  WireFormat::kYuyv,  WireFormat::kY16,
              WireFormat::kBgr24, WireFormat::kRgb24, WireFormat::kMjpeg};
    case PixelFormat::kMono16:
      return {WireFormat::kY16};
    case PixelFormat::kBgr8:
      return {WireFormat::kBgr24, WireFormat::kRgb24, WireFormat::kYuyv, WireFormat::kMjpeg,
              WireFormat::kGrey};
  }
  return {};
}

const char* to_string(ConvertStatus s) {
  switch (s) {
    case ConvertStatus::kOk:
      return "ok";
    case ConvertStatus::kShortBuffer:
      return "short buffer";
    case ConvertStatus::kDecodeFailed:
      return "MJPEG decode failed";
    case ConvertStatus::kSizeMismatch:
      return "decoded size differs from the negotiated one";
    case ConvertStatus::kUnsupported:
      return "unsupported conversion";
  }
  return "?";
}

ConvertStatus convert_image(const WireImage& in, cv::Mat& out) {
  PixelFormat to = PixelFormat::kMono8;
  switch (out.type()) {
    case CV_8UC1:
      to = PixelFormat::kMono8;
      break;
    case CV_16UC1:
      to = PixelFormat::kMono16;
      break;
    case CV_8UC3:
      to = PixelFormat::kBgr8;
      break;
    default:
      return ConvertStatus::kUnsupported;
  }
  if (!can_convert(in.format, to) || out.cols != in.width || out.rows != in.height) {
    return out.cols != in.width || out.rows != in.height ? ConvertStatus::kSizeMismatch
                                                         : ConvertStatus::kUnsupported;
  }
  if (in.format == WireFormat::kMjpeg) {
    if (in.bytes.empty()) return ConvertStatus::kShortBuffer;
    const cv::Mat encoded(1, static_cast<int>(in.bytes.size()), CV_8UC1,
                          const_cast<std::byte*>(in.bytes.data()));
    const int flags = (to == PixelFormat::kMono8 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR) |
                      cv::IMREAD_IGNORE_ORIENTATION;
    const auto dims = jpeg_dimensions(in.bytes);
    if (!dims) return ConvertStatus::kDecodeFailed;
    if (dims->first != in.width || dims->second != in.height) return ConvertStatus::kSizeMismatch;
    const uchar* slot = out.data;
    cv::Mat decoded = out;  // a header: decoding writes into the slot when the size matches
    try {
      cv::imdecode(encoded, flags, &decoded);
    } catch (const std::exception&) {  // cv::Exception, or bad_alloc on a corrupt frame
      return ConvertStatus::kDecodeFailed;
    }
    if (decoded.empty()) return ConvertStatus::kDecodeFailed;
    if (decoded.data != slot) return ConvertStatus::kSizeMismatch;  // it had to reallocate
    return ConvertStatus::kOk;
  }
  const std::size_t row_bytes =
      static_cast<std::size_t>(in.width) * bytes_per_wire_pixel(in.format);
  if (in.stride < row_bytes || in.height <= 0 ||
      in.bytes.size() < in.stride * static_cast<std::size_t>(in.height - 1) + row_bytes) {
    return ConvertStatus::kShortBuffer;
  }
  const cv::Mat src(in.height, in.width,
                    in.format == WireFormat::kGrey   ? CV_8UC1
                    : in.format == WireFormat::kY16  ? CV_16UC1
                    : in.format == WireFormat::kYuyv ? CV_8UC2
                                                     : CV_8UC3,
                    const_cast<std::byte*>(in.bytes.data()), in.stride);
  switch (in.format) {
    case WireFormat::kGrey:
      if (to == PixelFormat::kMono8) {
        src.copyTo(out);
      } else {
        cv::cvtColor(src, out, cv::COLOR_GRAY2BGR);
      }
      break;
    case WireFormat::kY16:
      if (to == PixelFormat::kMono16) {
        src.copyTo(out);  // little-endian on the wire and in memory (x86, ARM)
      } else {
        src.convertTo(out, CV_8U, 1.0 / 256.0);
      }
      break;
    case WireFormat::kYuyv:
      if (to == PixelFormat::kMono8) {
        cv::extractChannel(src, out, 0);  // Y is every other byte
      } else {
        cv::cvtColor(src, out, cv::COLOR_YUV2BGR_YUYV);
      }
      break;
    case WireFormat::kBgr24:
      if (to == PixelFormat::kBgr8) {
        src.copyTo(out);
      } else {
        cv::cvtColor(src, out, cv::COLOR_BGR2GRAY);
      }
      break;
    case WireFormat::kRgb24:
      cv::cvtColor(src, out, to == PixelFormat::kBgr8 ? cv::COLOR_RGB2BGR : cv::COLOR_RGB2GRAY);
      break;
    case WireFormat::kMjpeg:
      break;
  }
  return ConvertStatus::kOk;
}

}  // namespace livod::camera

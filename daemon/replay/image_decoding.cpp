#include "daemon/replay/image_decoding.hpp"

#include <fmt/core.h>

#include <cctype>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/error.hpp"

namespace livod::daemon::replay {

namespace rb = io::rosbag;

cv::Mat to_mono_or_bgr(const cv::Mat& in) {
  cv::Mat m = in;
  if (m.depth() == CV_16U) {
    // The high byte of every sample (no rounding up into the next grey level).
    cv::Mat high(m.rows, m.cols, CV_8UC(m.channels()));
    for (int y = 0; y < m.rows; ++y) {
      const auto* src = m.ptr<std::uint16_t>(y);
      auto* dst = high.ptr<std::uint8_t>(y);
      for (int i = 0; i < m.cols * m.channels(); ++i)
        dst[i] = static_cast<std::uint8_t>(src[i] >> 8);
    }
    m = high;
  } else if (m.depth() != CV_8U) {
    throw Error("unsupported pixel depth (8 or 16 bits per channel)");
  }
  if (m.channels() == 4) {
    cv::Mat bgr;
    cv::cvtColor(m, bgr, cv::COLOR_BGRA2BGR);
    m = bgr;
  } else if (m.channels() != 1 && m.channels() != 3) {
    throw Error("unsupported channel count " + std::to_string(m.channels()));
  }
  return m;
}

std::int64_t parse_seconds_ns(const std::string& text, const std::string& where) {
  // Times up to about 290 years fit the ns range with margin.
  constexpr double kMaxSeconds = 9.0e9;
  const bool plain = text.find_first_of("eE") == std::string::npos;
  try {
    if (!plain) {
      std::size_t used = 0;
      const double seconds = std::stod(text, &used);
      if (used != text.size() || !(std::abs(seconds) < kMaxSeconds)) {
        throw std::invalid_argument("range");
      }
      return static_cast<std::int64_t>(std::llround(seconds * 1e9));
    }
    const bool negative = !text.empty() && text[0] == '-';
    const std::string body = negative ? text.substr(1) : text;
    const auto dot = body.find('.');
    const std::string whole = body.substr(0, dot);
    std::string frac = dot == std::string::npos ? "" : body.substr(dot + 1);
    if (whole.empty() && frac.empty()) throw std::invalid_argument("empty");
    for (const char c : whole + frac) {
      if (std::isdigit(static_cast<unsigned char>(c)) == 0) throw std::invalid_argument("digit");
    }
    const std::int64_t seconds = whole.empty() ? 0 : std::stoll(whole);
    if (static_cast<double>(seconds) >= kMaxSeconds) throw std::invalid_argument("range");
    frac = (frac + "000000000").substr(0, 9);
    const std::int64_t ns = seconds * 1'000'000'000LL + std::stoll(frac);
    return negative ? -ns : ns;
  } catch (const std::exception&) {
    throw Error(where + ": '" + text + "' is not a time in seconds");
  }
}

cv::Mat decode_image_message(const rb::sensor_msgs::Image& m) {
  const std::string& e = m.encoding;
  int type = 0;
  int bayer = -1;
  int rgb_order = -1;
  if (e == "mono8" || e == "8UC1") {
    type = CV_8UC1;
  } else if (e == "mono16" || e == "16UC1") {
    type = CV_16UC1;
  } else if (e == "bgr8" || e == "8UC3") {
    type = CV_8UC3;
  } else if (e == "rgb8") {
    type = CV_8UC3;
    rgb_order = cv::COLOR_RGB2BGR;
  } else if (e == "bgra8" || e == "8UC4") {
    type = CV_8UC4;
  } else if (e == "rgba8") {
    type = CV_8UC4;
    rgb_order = cv::COLOR_RGBA2BGR;
  } else if (e == "bayer_rggb8") {
    // OpenCV names Bayer patterns by the second row's first two pixels.
    type = CV_8UC1;
    bayer = cv::COLOR_BayerBG2BGR;
  } else if (e == "bayer_bggr8") {
    type = CV_8UC1;
    bayer = cv::COLOR_BayerRG2BGR;
  } else if (e == "bayer_gbrg8") {
    type = CV_8UC1;
    bayer = cv::COLOR_BayerGR2BGR;
  } else if (e == "bayer_grbg8") {
    type = CV_8UC1;
    bayer = cv::COLOR_BayerGB2BGR;
  } else {
    throw Error("unsupported image encoding '" + e + "'");
  }
  // Sides beyond 64 k pixels are no camera image (and would not fit OpenCV's int sizes).
  constexpr std::uint32_t kMaxSide = 65536;
  if (m.width == 0 || m.height == 0 || m.width > kMaxSide || m.height > kMaxSide) {
    throw Error(fmt::format("image size {}x{} out of range", m.width, m.height));
  }
  const int w = static_cast<int>(m.width);
  const int h = static_cast<int>(m.height);
  const std::size_t row = static_cast<std::size_t>(w) * CV_ELEM_SIZE(type);
  if (w <= 0 || h <= 0 || m.step < row ||
      m.data.size() < static_cast<std::size_t>(m.step) * static_cast<std::size_t>(h - 1) + row) {
    throw Error(fmt::format("image {}x{} {} with step {} and {} bytes is inconsistent", w, h, e,
                            m.step, m.data.size()));
  }
  if (m.is_bigendian != 0 && CV_MAT_DEPTH(type) == CV_16U) {
    throw Error("big-endian 16-bit images are not supported");
  }
  const cv::Mat view(h, w, type, const_cast<std::uint8_t*>(m.data.data()), m.step);
  cv::Mat out;
  if (bayer >= 0) {
    cv::cvtColor(view, out, bayer);
  } else if (rgb_order >= 0) {
    cv::cvtColor(view, out, rgb_order);
  } else {
    out = view.clone();
  }
  return to_mono_or_bgr(out);
}

cv::Mat decode_compressed_image(const rb::sensor_msgs::CompressedImage& msg) {
  if (msg.data.empty()) throw Error("empty compressed image");
  cv::Mat raw;
  try {
    const cv::Mat bytes(1, static_cast<int>(msg.data.size()), CV_8UC1,
                        const_cast<std::uint8_t*>(msg.data.data()));
    raw = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw Error("cannot decode the '" + msg.format + "' image: " + e.what());
  }
  if (raw.empty()) throw Error("cannot decode the '" + msg.format + "' image");
  return to_mono_or_bgr(raw);
}

std::vector<std::pair<std::int64_t, std::string>> parse_timestamps_txt(std::string_view text,
                                                                       const std::string& source) {
  std::vector<std::pair<std::int64_t, std::string>> frames;
  std::istringstream in{std::string(text)};
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream fields(line);
    std::string time;
    std::string name;
    if (!(fields >> time)) continue;  // blank or comment
    const std::string where = source + ":" + std::to_string(number);
    if (!(fields >> name)) throw Error(where + ": expected '<time> <file>'");
    // Seconds with a decimal point or an exponent; a bare integer is nanoseconds (EuRoC style).
    std::int64_t ns = 0;
    if (time.find_first_of(".eE") != std::string::npos) {
      ns = parse_seconds_ns(time, where);
    } else {
      try {
        std::size_t used = 0;
        ns = std::stoll(time, &used);
        if (used != time.size()) throw std::invalid_argument("trailing");
      } catch (const std::exception&) {
        throw Error(where + ": '" + time + "' is neither seconds nor integer nanoseconds");
      }
    }
    frames.emplace_back(ns, name);
  }
  return frames;
}

std::vector<std::int64_t> parse_times_txt(std::string_view text, const std::string& source) {
  std::vector<std::int64_t> times;
  std::istringstream in{std::string(text)};
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    std::istringstream fields(line);
    std::string time;
    if (!(fields >> time) || time[0] == '#') continue;
    times.push_back(parse_seconds_ns(time, source + ":" + std::to_string(number)));
  }
  return times;
}

}  // namespace livod::daemon::replay

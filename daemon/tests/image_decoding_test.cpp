// Image replay's parsers and decoders (daemon/replay/image_decoding.hpp): timestamps files of plain
// image folders and ROS image messages.

#include "daemon/replay/image_decoding.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "core/error.hpp"

namespace livod::daemon::replay {
namespace {

namespace rb = io::rosbag;

TEST(ImageDecoding, TimestampsTxtSecondsAndNanoseconds) {
  const auto frames = parse_timestamps_txt(
      "# timestamp filename\n"
      "1403715273.262142 rgb/a.png\n"
      "\n"
      "1403715273362142001 rgb/b.png  # integer ns\n"
      "1.5e-1 c.png\n",
      "timestamps.txt");
  ASSERT_EQ(frames.size(), 3U);
  // Exact to the ns (a double would round an epoch time's last digits).
  EXPECT_EQ(frames[0].first, 1403715273262142000LL);
  EXPECT_EQ(frames[0].second, "rgb/a.png");
  EXPECT_EQ(frames[1].first, 1403715273362142001LL);
  EXPECT_EQ(frames[2].first, 150000000LL);
  EXPECT_THROW(parse_timestamps_txt("12.5\n", "t.txt"), Error);         // no file
  EXPECT_THROW(parse_timestamps_txt("12.5x a.png\n", "t.txt"), Error);  // not a number
  EXPECT_THROW(parse_timestamps_txt("1e30 a.png\n", "t.txt"), Error);   // beyond the ns range
  try {
    parse_timestamps_txt("1.0 a.png\nabc b.png\n", "t.txt");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("t.txt:2"), std::string::npos) << e.what();
  }
}

TEST(ImageDecoding, KittiTimes) {
  const auto t = parse_times_txt("0.000000e+00\n1.036400e-01\n0.2072\n", "times.txt");
  EXPECT_EQ(t, (std::vector<std::int64_t>{0, 103640000, 207200000}));
}

rb::sensor_msgs::Image message(const std::string& encoding, std::uint32_t w, std::uint32_t h,
                               std::uint32_t step, std::vector<std::uint8_t> data) {
  rb::sensor_msgs::Image m;
  m.encoding = encoding;
  m.width = w;
  m.height = h;
  m.step = step;
  m.data = std::move(data);
  return m;
}

TEST(ImageDecoding, RawEncodings) {
  // rgb8 comes out BGR.
  const cv::Mat rgb = decode_image_message(message("rgb8", 1, 1, 3, {10, 20, 30}));
  ASSERT_EQ(rgb.type(), CV_8UC3);
  EXPECT_EQ(rgb.at<cv::Vec3b>(0, 0), cv::Vec3b(30, 20, 10));
  // mono16 keeps the high byte; a padded step is honoured.
  const cv::Mat mono16 =
      decode_image_message(message("mono16", 2, 1, 6, {0x00, 0x12, 0xFF, 0xAB, 0xEE, 0xEE}));
  ASSERT_EQ(mono16.type(), CV_8UC1);
  EXPECT_EQ(mono16.at<std::uint8_t>(0, 0), 0x12);
  EXPECT_EQ(mono16.at<std::uint8_t>(0, 1), 0xAB);
  // Bayer is demosaiced to BGR.
  const cv::Mat bayer =
      decode_image_message(message("bayer_rggb8", 4, 4, 4, std::vector<std::uint8_t>(16, 100)));
  EXPECT_EQ(bayer.type(), CV_8UC3);
  EXPECT_EQ(bayer.at<cv::Vec3b>(1, 1), cv::Vec3b(100, 100, 100));
  // The pixels are copied (the bag reuses its buffer).
  auto m = message("mono8", 2, 2, 2, {1, 2, 3, 4});
  const cv::Mat copy = decode_image_message(m);
  m.data[0] = 99;
  EXPECT_EQ(copy.at<std::uint8_t>(0, 0), 1);
  // Inconsistent or unsupported messages are errors.
  EXPECT_THROW(decode_image_message(message("mono8", 4, 4, 4, {1, 2, 3})), Error);
  EXPECT_THROW(decode_image_message(message("mono8", 4, 1, 2, {1, 2, 3, 4})), Error);
  EXPECT_THROW(decode_image_message(message("yuv422", 2, 1, 4, {1, 2, 3, 4})), Error);
  EXPECT_THROW(decode_image_message(message("mono8", 100000, 1, 100000, {})), Error);
}

TEST(ImageDecoding, CompressedImages) {
  cv::Mat grey(3, 5, CV_8UC1);
  for (int i = 0; i < 15; ++i) grey.data[i] = static_cast<std::uint8_t>(i * 17);
  std::vector<std::uint8_t> png;
  ASSERT_TRUE(cv::imencode(".png", grey, png));
  rb::sensor_msgs::CompressedImage m;
  m.format = "mono8; png compressed";
  m.data = png;
  const cv::Mat out = decode_compressed_image(m);
  ASSERT_EQ(out.type(), CV_8UC1);
  EXPECT_EQ(cv::norm(out, grey, cv::NORM_INF), 0.0);
  m.data = {1, 2, 3, 4, 5};
  EXPECT_THROW(decode_compressed_image(m), Error);
  m.data.clear();
  EXPECT_THROW(decode_compressed_image(m), Error);
}

}  // namespace
}  // namespace livod::daemon::replay

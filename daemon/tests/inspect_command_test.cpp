// `livod inspect` on the real ROS1 bags of ../shared/data: what they hold and how replay reads
// each topic; a truncated copy is still inspected from its chunks.

#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "daemon/commands/command.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon {
namespace {

struct Output {
  int exit_code = -1;
  std::string text;
};

Output inspect(const std::vector<std::string>& files) {
  CLI::App app;
  CommandContext ctx;
  add_inspect_command(app, ctx);
  std::vector<std::string> args{"livod", "inspect"};
  args.insert(args.end(), files.begin(), files.end());
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  testing::internal::CaptureStdout();
  app.parse(static_cast<int>(argv.size()), argv.data());
  Output out;
  out.text = testing::internal::GetCapturedStdout();
  out.exit_code = ctx.exit_code;
  return out;
}

bool has_line_with(const std::string& text, const std::vector<std::string>& words) {
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    const std::string line = text.substr(start, end - start);
    bool all = true;
    for (const auto& w : words) all = all && line.find(w) != std::string::npos;
    if (all) return true;
    start = end + 1;
  }
  return false;
}

TEST(InspectCommand, BagsListTheirTopicsAndHowReplayReadsThem) {
  const Output out =
      inspect({livod::test::data_path("rosbag1/test1.bag").string(),
               livod::test::data_path("rosbag1/ouster_packets_512x10.bag").string()});
  ASSERT_EQ(out.exit_code, 0) << out.text;
  EXPECT_NE(out.text.find("ROS1 bag 2.0"), std::string::npos) << out.text;
  EXPECT_NE(out.text.find("index intact"), std::string::npos) << out.text;
  EXPECT_TRUE(has_line_with(out.text, {"/imu/data", "sensor_msgs/Imu", "dataset_imu"})) << out.text;
  EXPECT_TRUE(has_line_with(out.text, {"/fix", "sensor_msgs/NavSatFix", " -"})) << out.text;
  EXPECT_TRUE(has_line_with(
      out.text, {"/os_node0/lidar_packets", "ouster_ros/PacketMsg", "ouster (packets)"}))
      << out.text;
}

TEST(InspectCommand, TruncatedBagIsReadFromItsChunks) {
  const auto dir = livod::test::temp_dir("inspect_bag");
  const auto source = livod::test::data_path("rosbag1/test1.bag");
  std::ifstream in(source, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto cut = dir / "cut.bag";
  std::ofstream(cut, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size() * 2 / 3));
  const Output out = inspect({cut.string()});
  EXPECT_EQ(out.exit_code, 0) << out.text;
  EXPECT_NE(out.text.find("index damaged, rebuilt by scanning the chunks"), std::string::npos)
      << out.text;
  EXPECT_TRUE(has_line_with(out.text, {"/imu/data", "sensor_msgs/Imu"})) << out.text;
}

}  // namespace
}  // namespace livod::daemon

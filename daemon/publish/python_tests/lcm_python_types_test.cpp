// The Python types lcm-gen generates at build time decode a log written by the C++ publisher
// (docs/lcm.md, "Python"), with Debian's /usr/bin/python3 and no LCM Python module.

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "daemon/publish/lcm_publisher.hpp"
#include "tests/support/data_dir.hpp"
#include "tests/support/process.hpp"

namespace livod::daemon::publish {
namespace {

TEST(LcmPythonTypes, DecodeWhatTheCppPublisherLogged) {
  const auto dir = test::temp_dir("lcm_python");
  const auto log = dir / "cpp.lcmlog";
  {
    LcmOutputConfig config;
    config.url = "file://" + log.string() + "?mode=w";
    config.publish_cloud = true;
    config.cloud_max_points = 100;
    LcmPublisher publisher(config, Frames{"world", "hdl32.imu"});
    PoseRecord pose;
    pose.t = MappedTime(3'000'000'000);
    pose.status = PoseStatus::kDegenerate;
    pose.p_world_body = {0.5, 0.25, -1.0};
    pose.covariance(0, 0) = 0.125;
    ASSERT_TRUE(publisher.publish_pose(pose));
    pose.source = PoseSource::kImuPropagated;
    ASSERT_TRUE(publisher.publish_pose(pose));
    HealthRecord health;
    health.version = "0.1.0";
    health.sensors = {SensorHealthRecord{.name = "hdl32"}, SensorHealthRecord{.name = "xsens"}};
    ASSERT_TRUE(publisher.publish_health(health));
    CloudRecord cloud;
    for (int i = 0; i < 300; ++i) {
      const auto f = static_cast<float>(i);
      cloud.points.push_back({f, 0.5F * f, -f, 2.0F});
    }
    ASSERT_TRUE(publisher.publish_cloud(cloud));
  }
  const int status = test::run_process(
      {"/usr/bin/python3", LIVOD_PYTHON_DECODER, log.string()},
      {.output = dir / "python.txt", .environment = {"PYTHONPATH=" LIVOD_LCM_PYTHON_DIR}});
  const std::string output = test::read_text_file(dir / "python.txt");
  ASSERT_EQ(status, 0) << output;
  std::vector<std::string> lines;
  std::istringstream in(output);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("EVENT ", 0) == 0) lines.push_back(line);
  }
  ASSERT_EQ(lines.size(), 5u) << output;
  EXPECT_EQ(lines[0],
            "EVENT LIVOD_POSE livod.pose_t sequence=0 status=2 body_frame=hdl32.imu "
            "position=[0.5, 0.25, -1.0] covariance00=0.125");
  EXPECT_EQ(lines[1],
            "EVENT LIVOD_POSE_IMU livod.pose_t sequence=0 status=2 body_frame=hdl32.imu "
            "position=[0.5, 0.25, -1.0] covariance00=0.125");
  EXPECT_EQ(lines[2], "EVENT POSE_BODY bot_core.pose_t utime=3000000 pos=[0.5, 0.25, -1.0]");
  EXPECT_EQ(lines[3], "EVENT LIVOD_HEALTH livod.health_t sensors=['hdl32', 'xsens'] version=0.1.0");
  // 300 points decimated to 100: the last kept is point 297 (99 * 300 / 100).
  EXPECT_EQ(lines[4],
            "EVENT LIVOD_CLOUD livod.cloud_t fields=['x', 'y', 'z', 'intensity'] num_points=100 "
            "last=(297.0, 148.5, -297.0, 2.0)");
}

}  // namespace
}  // namespace livod::daemon::publish

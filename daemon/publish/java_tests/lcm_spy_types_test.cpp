// livod_lcmtypes.jar with LCM's Java runtime: a log written by the C++ publisher is decoded by
// LcmSpyCheck.java through lcm-spy's own type lookup (lcm.spy.LCMTypeDatabase over the CLASSPATH
// environment variable, as with `CLASSPATH=livod_lcmtypes.jar lcm-spy`), so lcm-spy finds every
// livod type by its fingerprint and decodes it to the same values.

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "daemon/publish/lcm_publisher.hpp"
#include "tests/support/data_dir.hpp"
#include "tests/support/process.hpp"

namespace livod::daemon::publish {
namespace {

std::vector<std::string> event_lines(const std::string& output) {
  std::vector<std::string> lines;
  std::istringstream in(output);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("EVENT ", 0) == 0) lines.push_back(line);
  }
  return lines;
}

bool has(const std::string& line, const std::string& part) {
  return line.find(part) != std::string::npos;
}

TEST(LcmSpyTypes, JavaDecodesEveryMessageTheCppPublisherLogged) {
  const auto dir = test::temp_dir("lcm_java");
  const auto log = dir / "cpp.lcmlog";
  {
    LcmOutputConfig config;
    config.url = "file://" + log.string() + "?mode=w";
    config.publish_cloud = true;
    config.cloud_max_points = 100;
    LcmPublisher publisher(config, Frames{"world", "os1.imu"});
    publisher.set_time_base(TimeBase{1'700'000'000'000'000'000});

    PoseRecord pose;
    pose.t = MappedTime(2'000'000'000);
    pose.filter_t = pose.t;
    pose.has_filter_update = true;
    pose.status = PoseStatus::kOk;
    pose.p_world_body = {1.5, -2.25, 3.125};
    pose.covariance(0, 0) = 0.25;
    ASSERT_TRUE(publisher.publish_pose(pose));
    pose.source = PoseSource::kImuPropagated;  // LIVOD_POSE_IMU and POSE_BODY
    ASSERT_TRUE(publisher.publish_pose(pose));

    HealthRecord health;
    health.unix_time_ns = 1'700'000'002'000'000'000;
    health.version = "0.1.0";
    SensorHealthRecord sensor;
    sensor.name = "os1";
    sensor.streams.push_back({"lidar"});
    health.sensors = {sensor};
    health.threads = {{"scheduler"}, {"publisher"}};
    health.channels = publisher.channel_counters();
    ASSERT_TRUE(publisher.publish_health(health));

    CloudRecord cloud;
    cloud.t = pose.t;
    cloud.points.resize(250);
    ASSERT_TRUE(publisher.publish_cloud(cloud));
  }

  const std::string classes = (dir / "classes").string();
  const int javac = test::run_process(
      {LIVOD_JAVAC, "-nowarn", "-cp", LIVOD_LCM_JAR, "-d", classes, LIVOD_JAVA_CHECK_SOURCE},
      {.output = dir / "javac.txt"});
  ASSERT_EQ(javac, 0) << test::read_text_file(dir / "javac.txt");

  // As lcm-spy runs: its class path (LCM's jar, jchart2d), livod's types found through CLASSPATH.
  const int java = test::run_process(
      {LIVOD_JAVA, "-cp", std::string(LIVOD_LCM_SPY_CLASSPATH) + ":" + classes, "LcmSpyCheck",
       log.string()},
      {.output = dir / "java.txt", .environment = {"CLASSPATH=" LIVOD_LCMTYPES_JAR}});
  const std::string output = test::read_text_file(dir / "java.txt");
  EXPECT_EQ(java, 0) << output;
  const auto lines = event_lines(output);
  ASSERT_EQ(lines.size(), 5u) << output;

  EXPECT_TRUE(has(lines[0], "EVENT LIVOD_POSE livod.pose_t reencoded")) << lines[0];
  EXPECT_TRUE(has(lines[0], " utime=1700000002000000 ")) << lines[0];
  EXPECT_TRUE(has(lines[0], " body_frame=os1.imu ")) << lines[0];
  EXPECT_TRUE(has(lines[0], " status=1 ")) << lines[0];
  EXPECT_TRUE(has(lines[0], " position=[1.5,-2.25,3.125] ")) << lines[0];
  EXPECT_TRUE(has(lines[0], " orientation=[1.0,0.0,0.0,0.0] ")) << lines[0];
  EXPECT_TRUE(has(lines[0], " covariance=[[0.25,0.0,")) << lines[0];
  EXPECT_TRUE(has(lines[1], "EVENT LIVOD_POSE_IMU livod.pose_t reencoded")) << lines[1];
  EXPECT_TRUE(has(lines[1], " source=1 ")) << lines[1];
  EXPECT_TRUE(has(lines[2], "EVENT POSE_BODY bot_core.pose_t reencoded")) << lines[2];
  EXPECT_TRUE(has(lines[2], " pos=[1.5,-2.25,3.125] ")) << lines[2];
  EXPECT_TRUE(has(lines[3], "EVENT LIVOD_HEALTH livod.health_t reencoded")) << lines[3];
  EXPECT_TRUE(has(lines[3], " version=0.1.0 ")) << lines[3];
  EXPECT_TRUE(has(lines[3], " sensors=[os1] ")) << lines[3];
  EXPECT_TRUE(has(lines[3], " threads=[scheduler,publisher] ")) << lines[3];
  EXPECT_TRUE(has(lines[3],
                  " channels=[LIVOD_POSE,LIVOD_POSE_IMU,POSE_BODY,LIVOD_HEALTH,"
                  "LIVOD_CLOUD]"))
      << lines[3];
  EXPECT_TRUE(has(lines[4], "EVENT LIVOD_CLOUD livod.cloud_t reencoded")) << lines[4];
  EXPECT_TRUE(has(lines[4], " fields=[x,y,z,intensity] ")) << lines[4];
  EXPECT_TRUE(has(lines[4], " num_points=100 ")) << lines[4];
  EXPECT_TRUE(has(lines[4], " data=bytes:1600")) << lines[4];
}

// Without livod's jar on CLASSPATH, lcm-spy's lookup finds nothing: the check above can fail.
TEST(LcmSpyTypes, WithoutTheJarNoTypeIsFound) {
  const auto dir = test::temp_dir("lcm_java_nojar");
  const auto log = dir / "cpp.lcmlog";
  {
    LcmOutputConfig config;
    config.url = "file://" + log.string() + "?mode=w";
    LcmPublisher publisher(config, Frames{"world", "imu"});
    ASSERT_TRUE(publisher.publish_pose(PoseRecord{}));
  }
  const std::string classes = (dir / "classes").string();
  ASSERT_EQ(test::run_process({LIVOD_JAVAC, "-nowarn", "-cp", LIVOD_LCM_JAR, "-d", classes,
                               LIVOD_JAVA_CHECK_SOURCE},
                              {.output = dir / "javac.txt"}),
            0)
      << test::read_text_file(dir / "javac.txt");
  const int java =
      test::run_process({LIVOD_JAVA, "-cp", std::string(LIVOD_LCM_SPY_CLASSPATH) + ":" + classes,
                         "LcmSpyCheck", log.string()},
                        {.output = dir / "java.txt", .environment = {"CLASSPATH="}});
  const std::string output = test::read_text_file(dir / "java.txt");
  EXPECT_EQ(java, 1) << output;
  const auto lines = event_lines(output);
  ASSERT_EQ(lines.size(), 1u) << output;
  EXPECT_TRUE(has(lines[0], "EVENT LIVOD_POSE NO_TYPE")) << lines[0];
}

}  // namespace
}  // namespace livod::daemon::publish

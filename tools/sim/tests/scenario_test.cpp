#include "tools/sim/scenario.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <limits>

#include "core/error.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/sim/runner.hpp"

namespace livod::sim {
namespace {

std::filesystem::path write(const std::string& name, const std::string& text) {
  const auto dir = test::temp_dir("scenario");
  const auto path = dir / name;
  std::ofstream(path) << text;
  return path;
}

TEST(Scenario, NamedScenariosAreListedAndConsistent) {
  const auto list = list_scenarios();
  ASSERT_GE(list.size(), 8u);
  for (const auto& [name, description] : list) {
    const Scenario s = make_scenario(name);
    EXPECT_EQ(s.name, name);
    EXPECT_FALSE(description.empty());
    ASSERT_FALSE(s.lidars.empty()) << name;
    bool body = s.can_imu && s.can_imu->name == s.body_imu;
    for (const auto& l : s.lidars) body = body || l.name == s.body_imu;
    EXPECT_TRUE(body) << name << ": body_imu names no sensor";
    // Starts static long enough for IMU initialisation.
    EXPECT_GE(s.trajectory.static_duration, 1.0) << name;
  }
  EXPECT_THROW(make_scenario("nope"), Error);
}

TEST(Scenario, StreetScenariosTravelAtLeast300m) {
  for (const char* name :
       {"street_vehicle_vlp16", "street_vehicle_hdl32e", "street_vehicle_os1_128"}) {
    const Scenario s = make_scenario(name);
    const Trajectory traj(s.trajectory);
    double length = 0.0;
    Eigen::Vector3d last = traj.at(0.0).p_world;
    for (double t = 0.05; t <= s.duration_s; t += 0.05) {
      const Eigen::Vector3d p = traj.at(t).p_world;
      length += (p - last).norm();
      last = p;
    }
    EXPECT_GE(length, 300.0) << name;
    EXPECT_LE(traj.at(s.duration_s).p_world.x(), s.street_length_m - 40.0)
        << name << " leaves the street";
  }
}

TEST(Scenario, YamlOverridesABaseScenario) {
  const auto path = write("ok.yaml", R"(
base: room_handheld_avia
name: short_avia
duration_s: 5
trajectory:
  x: {c0: 0.5, c1: 0.0, terms: [[1.0, 0.4, 0.0]]}
lidars:
  - {model: AVIA, name: avia, translation: [0.04, 0.02, -0.03], clock: {skew_ppm: 10}, link: {loss_probability: 0.01}}
cameras: []
)");
  const Scenario s = load_scenario_yaml(path);
  EXPECT_EQ(s.name, "short_avia");
  EXPECT_DOUBLE_EQ(s.duration_s, 5.0);
  ASSERT_EQ(s.lidars.size(), 1u);
  EXPECT_DOUBLE_EQ(s.lidars[0].clock.skew_ppm, 10.0);
  EXPECT_DOUBLE_EQ(s.lidars[0].link.loss_probability, 0.01);
  EXPECT_TRUE(s.cameras.empty());
  EXPECT_DOUBLE_EQ(s.trajectory.x.c0, 0.5);
  ASSERT_EQ(s.trajectory.x.terms.size(), 1u);
}

TEST(Scenario, YamlReportsEveryProblemAtOnce) {
  const auto path = write("bad.yaml", R"(
name: broken
world: moon
duration_s: -1
speed: 3
lidars:
  - {model: AVIA, translation: [1, 2], link: {loss_probability: 2}}
body_imu: nobody
)");
  try {
    load_scenario_yaml(path);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    for (const char* expected :
         {"scenario.world", "scenario.duration_s", "scenario.speed: unknown key",
          "lidars[0].name: required", "lidars[0].translation", "loss_probability",
          "scenario.body_imu"}) {
      EXPECT_NE(what.find(expected), std::string::npos) << "missing '" << expected << "' in\n"
                                                        << what;
    }
  }
}

// Issue 14: a duration beyond the street used to leave the LiDARs in empty space; the world now
// follows the trajectory, and durations that are not a finite positive number are refused.
TEST(Scenario, StreetGrowsWithTheDurationAndKeepsItsDefaultLength) {
  for (const char* name : {"street_vehicle_vlp16", "street_drone_os1_64"}) {
    const Scenario s = make_scenario(name);
    EXPECT_EQ(street_length_for(s, s.duration_s), s.street_length_m) << name;
    const double long_run = 300.0;
    const double length = street_length_for(s, long_run);
    const Trajectory traj(s.trajectory);
    EXPECT_GT(length, s.street_length_m) << name;
    // The street (from x = -20 m) still reaches 40 m beyond the last pose.
    EXPECT_LE(traj.at(long_run).p_world.x(), length - 20.0 - 40.0) << name;
  }
}

TEST(Scenario, RunRefusesDurationsThatAreNotFinitePositiveAndBounded) {
  const Scenario s = make_scenario("street_vehicle_vlp16");
  for (const double d :
       {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN(), -1.0,
        0.0, kMaxSimDurationS + 1.0}) {
    SimRunOptions o;
    o.out_dir = test::temp_dir("sim_bad_duration");
    o.duration_s = d;
    EXPECT_THROW(run_scenario(s, o), Error) << d;
  }
  const auto path = write("nan.yaml", "base: street_vehicle_vlp16\nduration_s: .nan\n");
  EXPECT_THROW(load_scenario_yaml(path), Error);
}

}  // namespace
}  // namespace livod::sim

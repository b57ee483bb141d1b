#pragma once
// Runs a scenario and writes its outputs to a folder:
//   <lidar>.pcap     wire-format capture (+ side files such as Ouster metadata JSON)
//   can_imu.log      candump log of the CAN IMU (if the scenario has one)
//   mav0/<camera>/   EuRoC/ASL: data.csv (with an exposure column), data/<ns>.png, sensor.yaml
//   groundtruth.txt  TUM, body (IMU) frame, host clock
//   config.yaml      a livod configuration replaying the folder
//   scenario.txt     what was simulated (human-readable)
//   sequence.bag     with write_bag: the same sequence as a ROS1 bag (tools/sim/bag_output.hpp)
// Host clock stamps are host_epoch (rounded to whole ns) + scenario time, exact to the ns.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "tools/sim/scenario.hpp"

namespace livod::sim {

// Longest simulation accepted (s): the outputs grow by about 860 MB per simulated minute with
// the 128-beam Ouster, so an hour is already tens of gigabytes.
constexpr double kMaxSimDurationS = 3600.0;

// The street length the world needs so that the trajectory stays inside it for `duration_s`
// (with room for the sensors' range ahead): the scenario's length, or longer.
double street_length_for(const Scenario& scenario, double duration_s);

struct SimRunOptions {
  std::filesystem::path out_dir;
  std::uint64_t seed = 1;
  // Overrides the scenario's duration; must be finite, > 0 and <= kMaxSimDurationS (run_scenario
  // throws otherwise). Street worlds grow to hold the trajectory (street_length_for).
  std::optional<double> duration_s;
  double host_epoch_s = 1'700'000'000.0;  // host clock (UTC) at scenario time 0
  bool write_images = true;
  bool write_bag = false;  // also sequence.bag: the folder as a ROS1 bag (tools/sim/bag_output.hpp)
  double chunk_s = 0.5;    // simulation step for memory-bounded generation
};

struct SimSensorReport {
  std::string name;
  std::string kind;            // "lidar", "camera", "can_imu", "bag"
  std::uint64_t messages = 0;  // datagrams, frames, CAN frames or bag messages written
  std::uint64_t dropped = 0;   // lost on the simulated link
  std::filesystem::path file;
};

struct SimRunReport {
  double simulated_s = 0.0;
  double wall_s = 0.0;
  std::vector<SimSensorReport> sensors;
  std::uint64_t groundtruth_poses = 0;
};

SimRunReport run_scenario(const Scenario& scenario, const SimRunOptions& options);

// The seed of one random stream of a run: derived from the run seed and the stream's name (a
// LiDAR's or camera's name; "<name>/clock", "<name>/link", "<name>/noise" for the CAN IMU), so
// that tests can rebuild exactly what the runner simulated.
std::uint64_t sensor_seed(std::uint64_t run_seed, const std::string& stream);

}  // namespace livod::sim

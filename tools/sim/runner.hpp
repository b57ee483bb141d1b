#pragma once
// Runs a scenario and writes its outputs to a folder:
//   <lidar name>.pcap (+ side files such as Ouster metadata JSON)  wire-format captures
//   can_imu.log                                                   candump log (if the scenario has
//   one) mav0/<camera>/data.csv, data/<ns>.png, sensor.yaml            EuRoC/ASL layout, exposure
//   per frame groundtruth.txt                                               TUM, body (IMU) frame,
//   host clock config.yaml                                                   a livod configuration
//   replaying it scenario.txt                                                  what was simulated
//   (human-readable)

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "tools/sim/scenario.hpp"

namespace livod::sim {

struct SimRunOptions {
  std::filesystem::path out_dir;
  std::uint64_t seed = 1;
  std::optional<double> duration_s;       // overrides the scenario's duration
  double host_epoch_s = 1'700'000'000.0;  // host clock (UTC) at scenario time 0
  bool write_images = true;
  double chunk_s = 0.5;  // simulation step for memory-bounded generation
};

struct SimSensorReport {
  std::string name;
  std::string kind;            // "lidar", "camera", "can_imu"
  std::uint64_t messages = 0;  // datagrams, frames or CAN frames written
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

}  // namespace livod::sim

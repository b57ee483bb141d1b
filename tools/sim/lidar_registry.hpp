#pragma once
// Simulated LiDAR models by name (the names `livod decode --model` accepts).

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "tools/sim/imu_model.hpp"
#include "tools/sim/sensor_clock.hpp"
#include "tools/sim/sensor_sim.hpp"

namespace livod::sim {

struct SimLidarOptions {
  RangeModel range;
  ClockFaults clock;
  LinkFaults link;
  bool imu = true;
  ImuNoiseParams imu_noise;
  std::uint64_t seed = 1;
  std::uint32_t sensor_ip = 0xC0A8010A;  // 192.168.1.10 (host order)
  std::uint32_t host_ip = 0xC0A80132;    // 192.168.1.50
  double host_epoch_s = 0.0;             // host clock reading at scenario time 0
  // Scans per second: 10 or 20 (Ouster lidar mode 1024x10 / 1024x20, Velodyne 600 / 1200 RPM;
  // Livox sensors stream continuously, their scan length is the decoder's frame_cut period).
  double scan_rate_hz = 10.0;
};

// Models the simulator can write; each entry is (model name, one-line description).
std::vector<std::pair<std::string, std::string>> simulated_lidar_models();

// True when the simulated model sends an internal IMU (false for unknown models).
bool simulated_lidar_has_imu(const std::string& model);

// Throws livod::Error naming the known models when `model` is not simulated.
std::unique_ptr<SimLidar> make_sim_lidar(const std::string& model, const SimLidarOptions& options);

}  // namespace livod::sim
